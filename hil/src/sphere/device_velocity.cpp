#include "lever/hil/device_velocity.hpp"

#include <numbers>

#include "lever/math/elementary.hpp"
#include "sphere_person.hpp"

namespace lever::hil {

Butterworth3 butterworth3(double cutoff_hz, double sample_hz) {
  // tan as lever::math's sin / cos: libm's tan may differ in its last bit between machines, and the coefficients
  // feed the seeded run.
  const double w = std::numbers::pi * cutoff_hz / sample_hz;
  const double k = math::sin(w) / math::cos(w);
  const double k2 = k * k, k3 = k2 * k;
  const double d = k3 + 2.0 * k2 + 2.0 * k + 1.0;
  return {k3 / d, (3.0 * k3 + 2.0 * k2 - 2.0 * k - 3.0) / d, (3.0 * k3 - 2.0 * k2 - 2.0 * k + 3.0) / d,
          (k3 - 2.0 * k2 + 2.0 * k - 1.0) / d};
}

// The history starts as a device at rest where the hand holds it: no start-up transient.
DeviceVelocity::DeviceVelocity(const SphereConfig& c, const Vec3& start)
    : chain_(c.velocity_chain), filter_(butterworth3(c.driver_cutoff_hz, 1.0 / kSphereTick)), x1_(start), x2_(start) {}

const Vec3& DeviceVelocity::update(const Vec3& x) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (chain_ == SphereVelocityChain::difference) {
      velocity_[i] = (x[i] - x1_[i]) / kSphereTick;
      continue;
    }
    // The driver's (3 x_k - 4 x_(k-1) + x_(k-2)) / 2T, as differences: exactly zero while the position stands
    // still (the driver's form leaves a rounding residue of 1e-15 there, far below any wire's step).
    const double u = (3.0 * (x[i] - x1_[i]) - (x1_[i] - x2_[i])) / (2.0 * kSphereTick);
    const double y = filter_.b * (u + 3.0 * u_[0][i] + 3.0 * u_[1][i] + u_[2][i]) - filter_.a1 * y_[0][i] -
                     filter_.a2 * y_[1][i] - filter_.a3 * y_[2][i];
    u_[2][i] = u_[1][i];
    u_[1][i] = u_[0][i];
    u_[0][i] = u;
    y_[2][i] = y_[1][i];
    y_[1][i] = y_[0][i];
    y_[0][i] = y;
    velocity_[i] = y;
  }
  x2_ = x1_;
  x1_ = x;
  return velocity_;
}

}  // namespace lever::hil
