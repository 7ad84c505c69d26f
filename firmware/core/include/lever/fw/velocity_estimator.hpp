#pragma once
// Lever speed from quantized position. The backward difference is the paper's noisy baseline (one encoder
// count per ms is 0.38 rad/s); the tracking loop (a type-2 PLL on angle) gives a smooth estimate whose
// bandwidth is a parameter.
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
  constexpr double update(double measured_angle, double dt) noexcept {
    if (!state_.primed || !(dt > 0.0)) {
      state_ = {measured_angle, 0.0, measured_angle, true};
      return 0.0;
    }
    if (config_.method == VelocityMethod::backward_difference) {
      state_.velocity = (measured_angle - state_.previous) / dt;
      state_.previous = measured_angle;
      return state_.velocity;
    }
    // theta' = w + kp e, w' = ki e with kp = 2 b, ki = b^2: error dynamics s^2 + 2bs + b^2.
    const double b = config_.bandwidth_rad_s;
    const double error = measured_angle - state_.angle;
    state_.velocity += b * b * error * dt;
    state_.angle += (state_.velocity + 2.0 * b * error) * dt;
    state_.previous = measured_angle;
    return state_.velocity;
  }

 private:
  Config config_;
  State state_;
};

}  // namespace lever::fw
