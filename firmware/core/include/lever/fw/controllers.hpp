#pragma once
// Control laws, each as Config (data, set once) + State (inspectable by logs and the HIL).
#include <cmath>

namespace lever::fw {

// Clamp to [-limit, limit]; NaN becomes 0, so no arithmetic accident can command torque.
constexpr double clamp_torque(double torque, double limit) noexcept {
  if (!(torque == torque)) return 0.0;
  if (torque > limit) return limit;
  if (torque < -limit) return -limit;
  return torque;
}

// TOP: track the reconstructed HSI motion. PD on position with velocity feed-forward.
class PositionController {
 public:
  struct Config {
    double kp = 40.0;            // N m / rad
    double kd = 0.6;             // N m s / rad
    double kff_velocity = 0.02;  // N m s / rad: cancels the lever's viscous friction
    // After arming, the TOP moves from where it is to where the HSI is at this speed at most, instead of
    // jumping there at full torque (after a reboot and homing the two can be a radian apart).
    double approach_speed_rad_s = 1.0;
  };
  struct State {
    double position_error = 0.0;
    double velocity_error = 0.0;
    double torque = 0.0;  // before the supervisor's limit
  };

  constexpr PositionController() noexcept : PositionController(Config{}) {}
  explicit constexpr PositionController(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }

  constexpr double update(double position_ref, double velocity_ref, double position, double velocity) noexcept {
    state_.position_error = position_ref - position;
    state_.velocity_error = velocity_ref - velocity;
    state_.torque =
        config_.kp * state_.position_error + config_.kd * state_.velocity_error + config_.kff_velocity * velocity_ref;
    return state_.torque;
  }

 private:
  Config config_;
  State state_;
};

// HSI: display the remote contact force on the operator's hand. Open loop by default (torque = force x arm);
// with the HSI's own strain gauge, a PI loop on the force error corrects friction and motor errors.
class ForceDisplay {
 public:
  struct Config {
    double lever_arm_m = 0.1;  // pivot to handle
    double gain = 1.0;         // force scaling from TOP to HSI
    bool closed_loop = false;
    double kp = 0.5;   // per unit force error
    double ki = 20.0;  // 1/s
    double integral_limit_n = 5.0;
    // Local viscous damping on the HSI, N m s/rad, applied only while a contact force is displayed: a
    // damped virtual wall keeps the delayed contact loop from bouncing, and free motion stays free of drag.
    double contact_damping_nms = 0.6;  // docs/hil-model.md, "HSI damping in contact"
    double contact_threshold_n = 0.1;  // displayed force above which the lever counts as in contact
  };
  struct State {
    double desired_force = 0.0;
    double force_error = 0.0;
    double integral = 0.0;
    double torque = 0.0;
  };

  constexpr ForceDisplay() noexcept : ForceDisplay(Config{}) {}
  explicit constexpr ForceDisplay(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }
  constexpr void reset() noexcept { state_ = {}; }

  // remote_force: reconstructed TOP contact force (N, positive = pushing into the wall).
  // own_force: the HSI gauge's reading of the hand force, when closed loop and available.
  // velocity: the HSI lever's, for the local damping.
  // The displayed torque opposes the operator's push, hence the minus sign.
  constexpr double update(double remote_force, const double* own_force, double velocity, double dt) noexcept {
    state_.desired_force = config_.gain * remote_force;
    double force = state_.desired_force;
    if (config_.closed_loop && own_force != nullptr) {
      state_.force_error = state_.desired_force - *own_force;
      state_.integral += config_.ki * state_.force_error * dt;
      if (state_.integral > config_.integral_limit_n) state_.integral = config_.integral_limit_n;
      if (state_.integral < -config_.integral_limit_n) state_.integral = -config_.integral_limit_n;
      force += config_.kp * state_.force_error + state_.integral;
    }
    const bool in_contact = force > config_.contact_threshold_n || force < -config_.contact_threshold_n;
    state_.torque = -force * config_.lever_arm_m - (in_contact ? config_.contact_damping_nms * velocity : 0.0);
    return state_.torque;
  }

 private:
  Config config_;
  State state_;
};

}  // namespace lever::fw
