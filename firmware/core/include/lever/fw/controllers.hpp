#pragma once
// Control laws, each as Config (data, set once) + State (inspectable by logs and the HIL).
#include <cmath>
#include <numbers>

#include "lever/math/elementary.hpp"

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
    // The reference's velocity reaches the D and the feed-forward through a first-order low-pass at this cut-off
    // (0: as received). The HSI's velocity is a quantized angle's difference or estimate; through k_d + k_ff its
    // one-count steps kick a pressing TOP off the wall (docs/hil-model.md, "The TOP's use of the reference's
    // velocity, derived").
    double reference_velocity_cutoff_hz = 0.0;
    // After arming, the TOP moves from where it is to where the HSI is at this speed at most, instead of
    // jumping there at full torque (after a reboot and homing the two can be a radian apart).
    double approach_speed_rad_s = 1.0;
  };
  struct State {
    double position_error = 0.0;
    double velocity_error = 0.0;
    double velocity_ref = 0.0;  // the reference's velocity after the low-pass
    double torque = 0.0;        // before the supervisor's limit
  };

  constexpr PositionController() noexcept : PositionController(Config{}) {}
  explicit constexpr PositionController(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }

  // The low-pass starts again from the next reference's velocity (on arming: the reference's history is gone).
  constexpr void reset() noexcept { primed_ = false; }

  // One tick of `dt` seconds.
  double update(double position_ref, double velocity_ref, double position, double velocity, double dt) noexcept {
    if (!primed_ || !(config_.reference_velocity_cutoff_hz > 0.0)) {
      primed_ = true;
      state_.velocity_ref = velocity_ref;
    } else {
      // exp() at every change of dt only: a fixed tick reuses alpha, with the same result as computing it anew.
      // lever::math's exp: the core's results do not depend on the board's libm.
      if (!(dt == alpha_dt_)) {
        alpha_dt_ = dt;
        alpha_ = 1.0 - math::exp(-2.0 * std::numbers::pi * config_.reference_velocity_cutoff_hz * dt);
      }
      state_.velocity_ref += alpha_ * (velocity_ref - state_.velocity_ref);
    }
    state_.position_error = position_ref - position;
    state_.velocity_error = state_.velocity_ref - velocity;
    state_.torque = config_.kp * state_.position_error + config_.kd * state_.velocity_error +
                    config_.kff_velocity * state_.velocity_ref;
    return state_.torque;
  }

 private:
  Config config_;
  State state_;
  bool primed_ = false;
  double alpha_dt_ = -1.0;
  double alpha_ = 1.0;
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
