#pragma once
// The CAN controller's fault confinement state as its driver reports it in error frames (linux/can/error.h):
// error-active, error-warning, error-passive, bus-off, and restarts after bus-off. Pure: fed the error frames
// a socket read, it keeps the state and the counts; nothing here touches the kernel.
#include <linux/can/error.h>

#include <cstdint>
#include <string_view>

#include "lever/board/socketcan.hpp"

namespace lever::board {

// In the order of severity: each is entered at a higher error count (ISO 11898-1: 96 warning, 128 passive,
// 256 bus-off).
enum class CanBusState : std::uint8_t { error_active, error_warning, error_passive, bus_off };

std::string_view name(CanBusState state) noexcept;  // "error-active", ... as `ip -details link` spells them

// The error classes the monitor interprets, for the socket's CAN_RAW_ERR_FILTER: state changes (controller,
// bus-off, restarted) and the errors that cause them (missing acknowledgement, bus and protocol errors,
// transmit timeouts). Arbitration lost is left out: it is normal on a shared bus.
inline constexpr std::uint32_t kMonitoredErrorClasses = CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_PROT | CAN_ERR_ACK |
                                                        CAN_ERR_BUSOFF | CAN_ERR_BUSERROR | CAN_ERR_RESTARTED;

struct CanErrorCounts {
  std::uint64_t error_frames = 0;     // every error frame seen
  std::uint64_t bus_off_count = 0;    // entries into bus-off
  std::uint64_t restarts = 0;         // the controller restarted after bus-off (by restart-ms or by hand)
  std::uint64_t warnings = 0;         // entries into error-warning
  std::uint64_t passives = 0;         // entries into error-passive
  std::uint64_t ack_errors = 0;       // frames nobody acknowledged
  std::uint64_t bus_errors = 0;       // bus or protocol errors (bit, stuff, form, CRC)
  std::uint64_t rx_overflows = 0;     // the controller's receive buffer overflowed: frames were lost
  std::uint64_t tx_timeouts = 0;      // the driver gave up on a transmission
  std::uint8_t tx_error_counter = 0;  // the controller's TEC and REC, from the last error frame that had them
  std::uint8_t rx_error_counter = 0;
};

class CanBusMonitor {
 public:
  void on_error_frame(const CanErrorFrame& frame) noexcept;
  // The interface was brought up again: its controller starts error-active (the drivers' open path), with no
  // error frame to say so.
  void on_controller_started() noexcept;

  CanBusState state() const noexcept { return state_; }
  const CanErrorCounts& counts() const noexcept { return counts_; }

 private:
  void enter(CanBusState next) noexcept;
  CanBusState state_ = CanBusState::error_active;
  CanErrorCounts counts_;
};

}  // namespace lever::board
