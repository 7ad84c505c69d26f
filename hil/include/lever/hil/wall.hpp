#pragma once
// The TOP's environment: a stiff wall as a spring-damper that pushes but never pulls (no sticking).
namespace lever::hil {

struct WallParams {
  double angle = 0.3;        // rad where the lever touches it
  double stiffness = 200.0;  // N m/rad: 20 kN/m at the 0.1 m tip, an aluminium block on a desk-top rig
  double damping = 0.3;      // N m s/rad
};

// Torque the wall exerts on the lever (negative: back out of the wall).
inline double wall_torque(const WallParams& w, double angle, double speed) {
  const double penetration = angle - w.angle;
  if (penetration <= 0.0) return 0.0;
  const double push = w.stiffness * penetration + w.damping * speed;
  return push > 0.0 ? -push : 0.0;
}

}  // namespace lever::hil
