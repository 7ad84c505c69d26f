#include "sphere_device.hpp"

namespace lever::hil {

SphereDevice::SphereDevice(const SphereConfig& c)
    : c_(c),
      tremor_rng_(c.seed * 4 + 3),
      tremor_(c.hand, c.device.mass_kg, tremor_rng_),
      explorer_(c.hand, c.sphere, c.seed * 4 + 4),
      x_(explorer_.start()),
      intent_(x_),
      intent_prev_(x_) {}

void SphereDevice::step(double t, const Vec3& displayed) {
  const double h = kSphereTick / c_.substeps;
  const double step = h / (c_.hand.mass_kg + c_.device.mass_kg);  // velocity change per newton and substep
  intent_prev_ = intent_;
  intent_ = explorer_.intent(t - kSphereTick);
  const Vec3 intent_speed = scale(difference(intent_, intent_prev_), 1.0 / kSphereTick);
  const Vec3 shake = tremor_.next();
  for (int s = 0; s < c_.substeps; ++s) {
    const double speed = norm(v_);
    const double friction = c_.device.friction_n / std::max(speed, c_.device.friction_linear_mps);
    for (std::size_t i = 0; i < 3; ++i) {
      const double f = c_.hand.stiffness * (intent_[i] - x_[i]) + c_.hand.damping * (intent_speed[i] - v_[i]) +
                       shake[i] + displayed[i] - friction * v_[i];
      v_[i] += f * step;
      x_[i] += v_[i] * h;
    }
  }
}

}  // namespace lever::hil
