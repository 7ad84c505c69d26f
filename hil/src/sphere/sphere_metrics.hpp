#pragma once
// What sphere-3dof measures: contact, saturation, the displayed force against the undistorted system's (eq. 11 at
// the position measured when the sample the display rests on was taken, SphereClocks) and against the force the TOP
// computed, and the TOP's position against the measured one its update was taken from.
#include <array>
#include <cstdint>

#include "lever/hil/sphere3dof.hpp"
#include "sphere_clocks.hpp"
#include "sphere_op.hpp"
#include "sphere_packets.hpp"
#include "sphere_top.hpp"

namespace lever::hil {

class SphereMetrics {
 public:
  SphereMetrics(const SphereConfig& c, const SphereDelays& delays, const SphereClocks& clocks);

  // After the OP sampled at its tick k.
  void op_sampled(std::uint64_t k, const SphereOp& op);
  // After the TOP's tick j.
  void top_stepped(std::uint64_t j, const SphereTop& top);
  // At the end of the OP's tick k.
  void step(std::uint64_t k, const SphereOp& op, const SphereTop& top, double device_speed);
  // The force the undistorted system would display at this tick (for the trace).
  const Vec3& reference() const { return reference_; }
  void finish(SphereResult& r, std::uint64_t ticks) const;

 private:
  void add_force(std::uint64_t k, const SphereOp& op);

  static constexpr std::size_t kHistory = 1024;
  const SphereConfig& c_;
  const SphereClocks& clocks_;
  std::array<Vec3, kHistory> top_force_history_{}, measured_history_{};
  Vec3 reference_{};
  std::uint64_t contact_ = 0, saturated_ = 0, violations_ = 0, downlink_violations_ = 0, zero_velocity_ = 0,
                position_samples_ = 0;
  double contact_force_sum_ = 0.0, force_sq_ = 0.0, position_sq_ = 0.0, speed_sum_ = 0.0, position_max_error_ = 0.0;
};

}  // namespace lever::hil
