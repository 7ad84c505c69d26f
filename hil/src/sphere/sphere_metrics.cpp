#include "sphere_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sphere_vec.hpp"

namespace lever::hil {

SphereMetrics::SphereMetrics(const SphereConfig& c, const SphereDelays& delays, const SphereClocks& clocks)
    : c_(c), clocks_(clocks) {
  // Two ticks on top of the round trip: the TOP's tick between the sample and the display, and a tick of slip.
  if (delays.up_ticks + delays.down_ticks + 2 >= static_cast<int>(kHistory))
    throw std::invalid_argument("sphere-3dof: link delay too long");
}

void SphereMetrics::op_sampled(std::uint64_t k, const SphereOp& op) { measured_history_[k % kHistory] = op.measured(); }

void SphereMetrics::top_stepped(std::uint64_t j, const SphereTop& top) {
  top_force_history_[j % kHistory] = top.force();
  const auto sampled = clocks_.op_tick_heard_by_top(j);
  if (!top.has_position() || !sampled) return;
  const double e = norm(difference(top.position(), measured_history_[*sampled % kHistory]));
  position_sq_ += e * e;
  position_max_error_ = std::max(position_max_error_, e);
  ++position_samples_;
}

void SphereMetrics::step(std::uint64_t k, const SphereOp& op, const SphereTop& top, double device_speed) {
  speed_sum_ += device_speed;
  const Vec3& velocity = op.velocity();
  if (velocity[0] == 0.0 && velocity[1] == 0.0 && velocity[2] == 0.0) ++zero_velocity_;
  const double force_n = norm(top.force());
  if (force_n > 0.0) {
    ++contact_;
    contact_force_sum_ += force_n;
  }
  if (force_n > c_.device.max_force_n) ++saturated_;
  add_force(k, op);
}

void SphereMetrics::add_force(std::uint64_t k, const SphereOp& op) {
  // Against the undistorted system: eq. (11) at the position measured at the sample the display rests on.
  const auto computed = clocks_.top_tick_heard_by_op(k);
  const auto sampled = computed ? clocks_.op_tick_heard_by_top(*computed) : std::nullopt;
  reference_ = sampled
                   ? saturate(sphere_force(c_.sphere, measured_history_[*sampled % kHistory]), c_.device.max_force_n)
                   : Vec3{};
  const double error = norm(difference(op.displayed(), reference_));
  force_sq_ += error * error;
  if (error > std::max(c_.jnd * norm(reference_), c_.jnd_absolute_n)) ++violations_;
  // Against the force the TOP computed at the tick the display rests on: the force direction's codec alone.
  const Vec3 sent_reference =
      computed ? saturate(top_force_history_[*computed % kHistory], c_.device.max_force_n) : Vec3{};
  const double sent_error = norm(difference(op.displayed(), sent_reference));
  if (sent_error > std::max(c_.jnd * norm(sent_reference), c_.jnd_absolute_n)) ++downlink_violations_;
}

void SphereMetrics::finish(SphereResult& r, std::uint64_t ticks) const {
  const double n = static_cast<double>(ticks);
  r.contact_share = static_cast<double>(contact_) / n;
  r.mean_contact_force_n = contact_ > 0 ? contact_force_sum_ / static_cast<double>(contact_) : 0.0;
  r.saturated_share = static_cast<double>(saturated_) / n;
  r.force_jnd_violation = static_cast<double>(violations_) / n;
  r.downlink_jnd_violation = static_cast<double>(downlink_violations_) / n;
  r.force_rmse_n = std::sqrt(force_sq_ / n);
  r.position_rmse_m = position_samples_ > 0 ? std::sqrt(position_sq_ / static_cast<double>(position_samples_)) : 0.0;
  r.position_max_error_m = position_max_error_;
  r.zero_velocity_share = static_cast<double>(zero_velocity_) / n;
  r.mean_speed_mps = speed_sum_ / n;
}

}  // namespace lever::hil
