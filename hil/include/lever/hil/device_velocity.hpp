#pragma once
// The sphere-3dof's device velocity as the OP reads it from its driver (docs/hil-model.md, "The velocity as a device
// driver gives it"): the open-source PHANToM Omni ROS driver's chain, a second-order backward difference of the
// quantized position and a third-order Butterworth low-pass (20 Hz there), per axis; or the one-tick difference of the
// quantized position, for comparison.
#include "lever/hil/sphere3dof.hpp"

namespace lever::hil {

// A third-order Butterworth low-pass by the bilinear transform with a prewarped cut-off:
// y_k = b (x_k + 3 x_(k-1) + 3 x_(k-2) + x_(k-3)) - a1 y_(k-1) - a2 y_(k-2) - a3 y_(k-3).
struct Butterworth3 {
  double b = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
};
Butterworth3 butterworth3(double cutoff_hz, double sample_hz);

class DeviceVelocity {
 public:
  DeviceVelocity(const SphereConfig& c, const Vec3& start);

  // The quantized position of this tick; returns the velocity the OP reads.
  const Vec3& update(const Vec3& measured);
  const Vec3& velocity() const { return velocity_; }

 private:
  SphereVelocityChain chain_;
  Butterworth3 filter_;
  Vec3 x1_, x2_;          // the positions one and two ticks back
  Vec3 u_[3]{}, y_[3]{};  // the filter's inputs and outputs one, two and three ticks back
  Vec3 velocity_{};
};

}  // namespace lever::hil
