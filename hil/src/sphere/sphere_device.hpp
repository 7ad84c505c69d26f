#pragma once
// The sphere-3dof's device in the operator's hand: the stylus tip's mass and friction, pulled by the hand's spring
// and damper toward where the person intends it, shaken by tremor, pushed by the force the device displays.
#include "lever/common/rng.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "sphere_person.hpp"

namespace lever::hil {

class SphereDevice {
 public:
  explicit SphereDevice(const SphereConfig& c);

  Vec3 start() const { return explorer_.start(); }
  // The hand and the device from the last tick to the one at `t`, under the force displayed since then.
  void step(double t, const Vec3& displayed);
  const Vec3& position() const { return x_; }
  double speed() const { return norm(v_); }

 private:
  const SphereConfig& c_;
  Rng tremor_rng_;
  Tremor tremor_;
  Explorer explorer_;
  Vec3 x_, v_{};
  Vec3 intent_, intent_prev_;
};

}  // namespace lever::hil
