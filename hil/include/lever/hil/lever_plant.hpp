#pragma once
// One lever's mechanics and motor, integrated at a fine step (semi-implicit Euler, default 10 kHz against the
// firmware's 1 kHz) so the stiff wall and the motor lag resolve between firmware ticks.
#include <cmath>

namespace lever::hil {

struct LeverPlantParams {
  double inertia = 2.0e-3;            // kg m^2: rotor, 10 cm lever and handle
  double radius = 0.1;                // m: pivot to the handle (HSI) or to the tip that meets the wall (TOP)
  double viscous = 0.01;              // N m s/rad
  double coulomb = 0.01;              // N m, bearing and brush friction
  double coulomb_speed = 0.02;        // rad/s: below this the Coulomb term fades in smoothly (no chattering)
  double motor_torque_limit = 1.5;    // N m: what the motor can physically give, above the firmware's 1 N m
  double motor_time_constant = 5e-4;  // s: current loop and winding inductance as a first-order lag
  // The mechanical end stop on the negative side, which homing drives into: a rubber bumper whose 20 N m/rad
  // (2 kN/m at the 0.1 m handle) gives a few millimetres under a hand's push. Infinite angle: no stop.
  double stop_angle = -0.6;      // rad
  double stop_stiffness = 20.0;  // N m/rad
  double stop_damping = 0.05;    // N m s/rad
};

class LeverPlant {
 public:
  explicit LeverPlant(const LeverPlantParams& p = {}, double angle = 0.0) : p_(p), angle_(angle) {}

  // Advance by dt under the commanded motor torque and an external torque (hand or wall).
  void advance(double commanded_torque, bool motor_enabled, double external_torque, double dt) {
    if (dt != step_) prepare(dt);  // the step is constant in a run: the divisions happen once
    const double target = motor_enabled ? clamp(commanded_torque, p_.motor_torque_limit) : 0.0;
    motor_torque_ += (target - motor_torque_) * motor_blend_;
    // Coulomb friction regularized linearly below coulomb_speed: as smooth as tanh for the integrator, and a
    // clamp costs far less than tanh at 20 evaluations per tick.
    const double slip = speed_ / p_.coulomb_speed;
    const double friction = p_.viscous * speed_ + p_.coulomb * (slip > 1.0 ? 1.0 : slip < -1.0 ? -1.0 : slip);
    speed_ += (motor_torque_ + external_torque - friction + stop_torque()) * dt_over_inertia_;
    angle_ += speed_ * dt;
  }

  // A hand gripping the handle moves with it and adds its inertia.
  void set_added_inertia(double j) {
    added_inertia_ = j;
    step_ = 0.0;
  }

  double angle() const { return angle_; }
  double speed() const { return speed_; }
  double motor_torque() const { return motor_torque_; }
  const LeverPlantParams& params() const { return p_; }

 private:
  static double clamp(double v, double limit) { return v > limit ? limit : v < -limit ? -limit : v; }
  // Pushes out of the stop, never pulls into it.
  double stop_torque() const {
    const double penetration = p_.stop_angle - angle_;
    if (penetration <= 0.0) return 0.0;
    const double push = p_.stop_stiffness * penetration - p_.stop_damping * speed_;
    return push > 0.0 ? push : 0.0;
  }
  void prepare(double dt) {
    step_ = dt;
    motor_blend_ = dt / (p_.motor_time_constant + dt);
    dt_over_inertia_ = dt / (p_.inertia + added_inertia_);
  }
  LeverPlantParams p_;
  double angle_ = 0.0;
  double speed_ = 0.0;
  double motor_torque_ = 0.0;
  double added_inertia_ = 0.0;
  double step_ = 0.0;
  double motor_blend_ = 0.0;
  double dt_over_inertia_ = 0.0;
};

}  // namespace lever::hil
