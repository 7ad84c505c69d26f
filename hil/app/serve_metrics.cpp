#include "serve_metrics.hpp"

#include <algorithm>
#include <cmath>

namespace lever::hil {

void ServeMetrics::step(const PairHeard& heard, const ServeTick& s, const World& world, std::uint64_t motion_sent,
                        std::uint64_t force_sent, double displayed) {
  if (!heard.hsi) ++extras_.hsi_silent_ms;
  if (!heard.top) ++extras_.top_silent_ms;
  if (!heard.both_armed) return;
  const double dp = world.top().angle() - world.hsi().angle();
  metrics_.add_armed_tick(motion_sent, force_sent, dp, displayed, s.measured, s.contact);
  extras_.max_position_error_rad = std::max(extras_.max_position_error_rad, std::fabs(dp));
  extras_.max_displayed_force_n = std::max(extras_.max_displayed_force_n, displayed);
  if (s.contact > 0.0) extras_.hsi_torque_in_contact_sum += s.hsi_command.enable ? s.hsi_command.torque_nm : 0.0;
}

}  // namespace lever::hil
