#include "lever/board/can_bus_monitor.hpp"

namespace lever::board {

std::string_view name(CanBusState state) noexcept {
  switch (state) {
    case CanBusState::error_active:
      return "error-active";
    case CanBusState::error_warning:
      return "error-warning";
    case CanBusState::error_passive:
      return "error-passive";
    case CanBusState::bus_off:
      return "bus-off";
  }
  return "unknown";
}

void CanBusMonitor::enter(CanBusState next) noexcept {
  if (next == state_) return;
  switch (next) {
    case CanBusState::error_warning:
      ++counts_.warnings;
      break;
    case CanBusState::error_passive:
      ++counts_.passives;
      break;
    case CanBusState::bus_off:
      ++counts_.bus_off_count;
      break;
    case CanBusState::error_active:
      break;
  }
  state_ = next;
}

void CanBusMonitor::on_error_frame(const CanErrorFrame& frame) noexcept {
  ++counts_.error_frames;
  const std::uint32_t classes = frame.classes;
  if (classes & CAN_ERR_CNT) {
    counts_.tx_error_counter = frame.data[6];
    counts_.rx_error_counter = frame.data[7];
  }
  if (classes & CAN_ERR_ACK) ++counts_.ack_errors;
  // Drivers set both for one bus error (PROT says where, BUSERROR that it happened): counted once.
  if (classes & (CAN_ERR_PROT | CAN_ERR_BUSERROR)) ++counts_.bus_errors;
  if (classes & CAN_ERR_TX_TIMEOUT) ++counts_.tx_timeouts;
  if (classes & CAN_ERR_CRTL) {
    const std::uint8_t status = frame.data[1];
    if (status & CAN_ERR_CRTL_RX_OVERFLOW) ++counts_.rx_overflows;
    // The kernel (can_change_state) puts the new state's bits for the worse of the two directions in one
    // frame, and CAN_ERR_CRTL_ACTIVE when it fell back to error-active; a frame with none of these (an
    // overflow alone) changes no state.
    if (status & (CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_PASSIVE)) {
      enter(CanBusState::error_passive);
    } else if (status & (CAN_ERR_CRTL_TX_WARNING | CAN_ERR_CRTL_RX_WARNING)) {
      enter(CanBusState::error_warning);
    } else if (status & CAN_ERR_CRTL_ACTIVE) {
      enter(CanBusState::error_active);
    }
  }
  if (classes & CAN_ERR_RESTARTED) {
    ++counts_.restarts;
    enter(CanBusState::error_active);
  }
  // Last, so that bus-off wins over anything else in the same frame: it is the state that stops the lever.
  if (classes & CAN_ERR_BUSOFF) enter(CanBusState::bus_off);
}

void CanBusMonitor::on_controller_started() noexcept { enter(CanBusState::error_active); }

}  // namespace lever::board
