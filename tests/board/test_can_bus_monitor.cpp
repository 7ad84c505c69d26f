// CanBusMonitor on the error frames drivers send (linux/can/error.h), built by hand: every state, every count,
// and what a frame without state bits leaves alone. The same path on the kernel's own error frames is in
// test_board_can.cpp (guest).
#include <linux/can/error.h>

#include <catch2/catch.hpp>

#include "lever/board/can_bus_monitor.hpp"

using lever::board::CanBusMonitor;
using lever::board::CanBusState;
using lever::board::CanErrorFrame;

namespace {

CanErrorFrame controller(std::uint8_t status) {
  CanErrorFrame f;
  f.classes = CAN_ERR_CRTL;
  f.data[1] = status;
  return f;
}

CanErrorFrame of_class(std::uint32_t classes) {
  CanErrorFrame f;
  f.classes = classes;
  return f;
}

}  // namespace

TEST_CASE("the controller's state follows its error frames", "[can_bus_monitor]") {
  CanBusMonitor m;
  CHECK(m.state() == CanBusState::error_active);
  m.on_error_frame(controller(CAN_ERR_CRTL_TX_WARNING));
  CHECK(m.state() == CanBusState::error_warning);
  m.on_error_frame(controller(CAN_ERR_CRTL_RX_PASSIVE));
  CHECK(m.state() == CanBusState::error_passive);
  m.on_error_frame(of_class(CAN_ERR_BUSOFF));
  CHECK(m.state() == CanBusState::bus_off);
  m.on_error_frame(of_class(CAN_ERR_RESTARTED));
  CHECK(m.state() == CanBusState::error_active);
  m.on_error_frame(controller(CAN_ERR_CRTL_RX_WARNING));
  CHECK(m.state() == CanBusState::error_warning);
  m.on_error_frame(controller(CAN_ERR_CRTL_ACTIVE));
  CHECK(m.state() == CanBusState::error_active);

  const auto& c = m.counts();
  CHECK(c.error_frames == 6);
  CHECK(c.warnings == 2);
  CHECK(c.passives == 1);
  CHECK(c.bus_off_count == 1);
  CHECK(c.restarts == 1);
}

TEST_CASE("a state is counted once when it is entered, not for every frame in it", "[can_bus_monitor]") {
  CanBusMonitor m;
  m.on_error_frame(controller(CAN_ERR_CRTL_TX_PASSIVE));
  m.on_error_frame(controller(CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_PASSIVE));
  m.on_error_frame(of_class(CAN_ERR_BUSOFF));
  m.on_error_frame(of_class(CAN_ERR_BUSOFF));
  CHECK(m.counts().passives == 1);
  CHECK(m.counts().bus_off_count == 1);
  CHECK(m.counts().error_frames == 4);
}

TEST_CASE("passive outranks warning in one frame, and bus-off outranks everything", "[can_bus_monitor]") {
  CanBusMonitor m;
  m.on_error_frame(controller(CAN_ERR_CRTL_TX_WARNING | CAN_ERR_CRTL_RX_PASSIVE));
  CHECK(m.state() == CanBusState::error_passive);
  CanErrorFrame both = controller(CAN_ERR_CRTL_ACTIVE);
  both.classes |= CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
  m.on_error_frame(both);
  CHECK(m.state() == CanBusState::bus_off);
}

TEST_CASE("frames without state bits change no state but are counted by kind", "[can_bus_monitor]") {
  CanBusMonitor m;
  m.on_error_frame(controller(CAN_ERR_CRTL_TX_WARNING));
  m.on_error_frame(controller(CAN_ERR_CRTL_RX_OVERFLOW));
  CHECK(m.state() == CanBusState::error_warning);
  CanErrorFrame bus = of_class(CAN_ERR_PROT | CAN_ERR_BUSERROR | CAN_ERR_ACK | CAN_ERR_CNT);
  bus.data[6] = 97;
  bus.data[7] = 3;
  m.on_error_frame(bus);
  m.on_error_frame(of_class(CAN_ERR_TX_TIMEOUT));
  CHECK(m.state() == CanBusState::error_warning);
  const auto& c = m.counts();
  CHECK(c.rx_overflows == 1);
  CHECK(c.bus_errors == 1);  // PROT and BUSERROR are one bus error
  CHECK(c.ack_errors == 1);
  CHECK(c.tx_timeouts == 1);
  CHECK(c.tx_error_counter == 97);
  CHECK(c.rx_error_counter == 3);
  CHECK(c.error_frames == 4);
}

TEST_CASE("the error counters are taken only from frames that carry them", "[can_bus_monitor]") {
  CanBusMonitor m;
  CanErrorFrame with = of_class(CAN_ERR_CRTL | CAN_ERR_CNT);
  with.data[1] = CAN_ERR_CRTL_TX_WARNING;
  with.data[6] = 96;
  m.on_error_frame(with);
  CanErrorFrame without = of_class(CAN_ERR_ACK);
  without.data[6] = 200;
  m.on_error_frame(without);
  CHECK(m.counts().tx_error_counter == 96);
}

TEST_CASE("a controller brought up again is error-active", "[can_bus_monitor]") {
  CanBusMonitor m;
  m.on_error_frame(of_class(CAN_ERR_BUSOFF));
  m.on_controller_started();
  CHECK(m.state() == CanBusState::error_active);
  CHECK(m.counts().restarts == 0);  // a restart is what the driver reports after bus-off, not an up
}

TEST_CASE("states are named as ip -details link spells them", "[can_bus_monitor]") {
  CHECK(name(CanBusState::error_active) == "error-active");
  CHECK(name(CanBusState::error_warning) == "error-warning");
  CHECK(name(CanBusState::error_passive) == "error-passive");
  CHECK(name(CanBusState::bus_off) == "bus-off");
}

TEST_CASE("the classes asked of the kernel are the ones the monitor reads", "[can_bus_monitor]") {
  using lever::board::kMonitoredErrorClasses;
  for (const std::uint32_t c : {CAN_ERR_CRTL, CAN_ERR_BUSOFF, CAN_ERR_RESTARTED, CAN_ERR_ACK, CAN_ERR_BUSERROR,
                                CAN_ERR_PROT, CAN_ERR_TX_TIMEOUT}) {
    CHECK((kMonitoredErrorClasses & c) == c);
  }
  CHECK((kMonitoredErrorClasses & CAN_ERR_LOSTARB) == 0);
}
