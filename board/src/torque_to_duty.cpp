#include "lever/board/torque_to_duty.hpp"

#include <algorithm>
#include <cmath>

namespace lever::board {

TorqueToDuty::TorqueToDuty(const PwmMotorConfig& config) noexcept
    : full_duty_nm_(config.gear_ratio * config.torque_constant_nm_per_a * config.full_scale_current_a),
      max_duty_(config.max_duty),
      deadband_nm_(config.deadband_nm),
      period_ns_(static_cast<double>(config.period_ns)),
      positive_only_(config.positive_torque_only) {}

DutySetpoint TorqueToDuty::operator()(double torque_nm) const noexcept {
  const double magnitude = std::fabs(torque_nm);
  // Written so that a NaN fails it too.
  if (!(magnitude >= deadband_nm_) || magnitude == 0.0) return {};
  const bool negative = torque_nm < 0.0;
  if (negative && positive_only_) return {};
  const double duty = std::min(magnitude / full_duty_nm_, max_duty_);
  const double ns = std::min(std::round(duty * period_ns_), period_ns_);
  return {static_cast<std::uint32_t>(ns), negative};
}

}  // namespace lever::board
