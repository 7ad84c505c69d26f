#pragma once
// Fault bits: stable numbers (they travel in heartbeats), latched by the supervisor until re-armed.
#include <cstdint>

namespace lever::fw {

enum class Fault : std::uint16_t {
  comms_timeout = 1u << 0,    // the peer was silent longer than the timeout
  encoder = 1u << 1,          // illegal quadrature transitions past the threshold
  force_stale = 1u << 2,      // no fresh strain-gauge sample within the staleness window
  force_saturated = 1u << 3,  // the strain gauge reads at its range limit
  motor_driver = 1u << 4,     // the driver reports a fault
  torque_limit = 1u << 5,     // the controller demanded more than the limit for too long
  position_limit = 1u << 6,   // the lever left its allowed range
};

using FaultBits = std::uint16_t;

constexpr FaultBits bit(Fault f) noexcept { return static_cast<FaultBits>(f); }
constexpr bool has(FaultBits bits, Fault f) noexcept { return (bits & bit(f)) != 0; }

}  // namespace lever::fw
