#pragma once
// Fault bits: stable numbers, on the wire in every heartbeat (common/protocol/lever.dbc, signal Faults). A
// lever latches them until a re-arm whose checks pass.
#include <cstdint>
#include <string_view>

namespace lever::protocol {

enum class Fault : std::uint16_t {
  comms_timeout = 1u << 0,    // the peer was silent longer than the timeout
  encoder = 1u << 1,          // illegal quadrature transitions past the threshold, or edges lost
  force_stale = 1u << 2,      // no fresh strain-gauge sample within the staleness window
  force_saturated = 1u << 3,  // the strain gauge reads at its range limit
  motor_driver = 1u << 4,     // the driver reports a fault
  torque_limit = 1u << 5,     // the controller demanded more than the limit for too long
  position_limit = 1u << 6,   // the lever left its allowed range
  timing = 1u << 7,           // a step came later than the hard bound, or the clock went back
  homing = 1u << 8,           // homing gave up: no stall or index within its travel or time
  peer_state = 1u << 9,       // the peer left the armed state while this lever was armed (disarm, fault, reboot)
  can_bus = 1u << 10,         // the CAN controller is bus-off, or its interface is down or gone
};

using FaultBits = std::uint16_t;

inline constexpr Fault kAllFaults[] = {Fault::comms_timeout,   Fault::encoder,      Fault::force_stale,
                                       Fault::force_saturated, Fault::motor_driver, Fault::torque_limit,
                                       Fault::position_limit,  Fault::timing,       Fault::homing,
                                       Fault::peer_state,      Fault::can_bus};

constexpr FaultBits bit(Fault f) noexcept { return static_cast<FaultBits>(f); }
constexpr bool has(FaultBits bits, Fault f) noexcept { return (bits & bit(f)) != 0; }

// Names as logs, the stats line and the docs spell them.
constexpr std::string_view name(Fault f) noexcept {
  switch (f) {
    case Fault::comms_timeout:
      return "comms_timeout";
    case Fault::encoder:
      return "encoder";
    case Fault::force_stale:
      return "force_stale";
    case Fault::force_saturated:
      return "force_saturated";
    case Fault::motor_driver:
      return "motor_driver";
    case Fault::torque_limit:
      return "torque_limit";
    case Fault::position_limit:
      return "position_limit";
    case Fault::timing:
      return "timing";
    case Fault::homing:
      return "homing";
    case Fault::peer_state:
      return "peer_state";
    case Fault::can_bus:
      return "can_bus";
  }
  return "unknown";
}

}  // namespace lever::protocol
