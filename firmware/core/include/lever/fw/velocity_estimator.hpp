#pragma once
// Lever speed from quantized position. The backward difference is the paper's noisy baseline (one encoder
// count per ms is 0.38 rad/s); the tracking loop (a type-2 loop on angle) gives a smooth estimate whose
// bandwidth is a parameter.
#include <cmath>
#include <cstdint>

namespace lever::fw {

enum class VelocityMethod : std::uint8_t { backward_difference = 0, tracking_loop = 1 };

class VelocityEstimator {
 public:
  struct Config {
    VelocityMethod method = VelocityMethod::tracking_loop;
    double bandwidth_rad_s = 300.0;  // tracking loop: both poles at -bandwidth (critically damped)
  };
  struct State {
    double angle = 0.0;     // tracking loop's angle estimate
    double velocity = 0.0;  // output
    double previous = 0.0;  // backward difference's last angle
    bool primed = false;
  };

  constexpr VelocityEstimator() noexcept : VelocityEstimator(Config{}) {}
  explicit constexpr VelocityEstimator(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }

  // New measured angle after dt seconds; returns the velocity estimate in rad/s.
  //
  // The tracking loop is integrated exactly over dt, with the measurement taken to move linearly from the
  // last sample to this one, not by an explicit Euler step: Euler diverged once dt stayed above about 2.8 ms
  // at 300 rad/s, and one 20 ms scheduling hiccup turned 1 rad/s into 37 rad/s. With the error
  // e = measured - angle, velocity w and the measurement's slope s over the step,
  //   e' = -2b e - w + s,  w' = b^2 e.
  // The matrix M has the double eigenvalue -b, so N = M + bI satisfies N^2 = 0 and
  //   exp(M t) = exp(-b t) (I + N t):
  // both poles stay at exp(-b dt) < 1 for every dt, and a ramp is tracked with zero error at any dt, so a
  // late tick neither blows the estimate up nor drags it toward zero.
  double update(double measured_angle, double dt) noexcept {
    if (!state_.primed || !(dt > 0.0)) {
      state_ = {measured_angle, 0.0, measured_angle, true};
      return 0.0;
    }
    if (config_.method == VelocityMethod::backward_difference) {
      state_.velocity = (measured_angle - state_.previous) / dt;
      state_.previous = measured_angle;
      return state_.velocity;
    }
    const double b = config_.bandwidth_rad_s;
    if (dt != cached_dt_) {  // one exp() per change of step, not per tick
      cached_dt_ = dt;
      decay_ = std::exp(-b * dt);
      // The forcing by the slope: integral of exp(M t) over the step, applied to (s, 0).
      const double i0 = (1.0 - decay_) / b;
      const double i1 = (1.0 - decay_ * (1.0 + b * dt)) / (b * b);
      slope_to_error_ = i0 - b * i1;
      slope_to_velocity_ = b * b * i1;
    }
    const double slope = (measured_angle - state_.previous) / dt;
    const double e = state_.previous - state_.angle;
    const double w = state_.velocity;
    const double e_next = decay_ * (e * (1.0 - b * dt) - w * dt) + slope * slope_to_error_;
    state_.velocity = decay_ * (w * (1.0 + b * dt) + b * b * dt * e) + slope * slope_to_velocity_;
    state_.angle = measured_angle - e_next;
    state_.previous = measured_angle;
    return state_.velocity;
  }

 private:
  Config config_;
  State state_;
  double cached_dt_ = 0.0;
  double decay_ = 1.0;
  double slope_to_error_ = 0.0;
  double slope_to_velocity_ = 0.0;
};

}  // namespace lever::fw
