#pragma once
// Lever speed from quantized position. The backward difference is the paper's noisy baseline (one encoder
// count per ms is 0.38 rad/s); the tracking loop (a type-2 loop on angle) gives a smooth estimate whose
// bandwidth is a parameter. Its integrator's state lags the angle's rate as a second-order low-pass; the rate of
// its angle estimate (the integrator plus the proportional path on the error) lags less and passes more of the
// encoder's quantization: a position loop's D that needs phase more than quiet takes that (docs/hil-model.md,
// "The TOP's velocity estimate, derived again").
#include <cstdint>
#include <string_view>

#include "lever/fw/tick.hpp"

namespace lever::fw {

enum class VelocityMethod : std::uint8_t { backward_difference = 0, tracking_loop = 1, tracking_loop_rate = 2 };

inline constexpr VelocityMethod kAllVelocityMethods[] = {
    VelocityMethod::tracking_loop, VelocityMethod::tracking_loop_rate, VelocityMethod::backward_difference};

// The one spelling of each method: lever-fw's configuration parses and prints it, tests print it.
constexpr std::string_view name(VelocityMethod m) noexcept {
  switch (m) {
    case VelocityMethod::backward_difference:
      return "backward_difference";
    case VelocityMethod::tracking_loop:
      return "tracking_loop";
    case VelocityMethod::tracking_loop_rate:
      return "tracking_loop_rate";
  }
  return "unknown";
}

class VelocityEstimator {
 public:
  struct Config {
    VelocityMethod method = VelocityMethod::tracking_loop;
    double bandwidth_rad_s = 300.0;  // tracking loop: both poles at -bandwidth (critically damped)
  };
  // The tracking loop's Euler step at one period T is stable only for b T below 2 sqrt(2) - 2: its error
  // dynamics (trace 2 - 2bT - (bT)^2, determinant 1 - 2bT) put a pole at -1 where (bT)^2 + 4 bT - 4 = 0. Beyond
  // it the estimate rings at the Nyquist frequency and grows; near it, it amplifies the encoder's quantization there
  // thousands of times (docs/firmware.md, "Timing bounds").
  static constexpr double kStableBandwidthTimesPeriod = 0.82842712474619;
  static constexpr double kMaxStableBandwidthRadS = kStableBandwidthTimesPeriod / kSecondsPerTick;
  struct State {
    double angle = 0.0;     // tracking loop's angle estimate
    double velocity = 0.0;  // the tracking loop's integrator (the backward difference's output)
    double rate = 0.0;      // the tracking loop's angle estimate's rate over its last step
    double previous = 0.0;  // backward difference's last angle
    bool primed = false;
  };

  constexpr VelocityEstimator() noexcept : VelocityEstimator(Config{}) {}
  explicit constexpr VelocityEstimator(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }

  // New measured angle after dt seconds; returns the velocity estimate in rad/s.
  //
  // The tracking loop is a discrete loop designed at the 1 ms period (Euler on the continuous type-2 loop,
  // stable with margin at b dt = 0.3). A step that comes late is not one Euler step of the whole interval:
  // that diverged once dt stayed above about 2.8 ms at 300 rad/s, and one 20 ms scheduling hiccup turned
  // 1 rad/s into 37 rad/s. It is run as sub-steps of at most one period over the measurement interpolated
  // linearly across the gap, so every interval gives the designed loop's stable response; a gap longer
  // than kMaxSubsteps periods (the lever has long since latched TIMING) restarts the estimate from the
  // backward difference over the gap, which bounds the work per call.
  double update(double measured_angle, double dt) noexcept {
    if (!state_.primed || !(dt > 0.0)) {
      state_ = {measured_angle, 0.0, 0.0, measured_angle, true};
      return 0.0;
    }
    const double previous = state_.previous;
    state_.previous = measured_angle;
    if (config_.method == VelocityMethod::backward_difference) {
      state_.velocity = (measured_angle - previous) / dt;
      return state_.velocity;
    }
    const double periods = dt * (1.0 / kSecondsPerTick);  // a constant: no division per tick
    if (periods > static_cast<double>(kMaxSubsteps)) {
      state_.velocity = state_.rate = (measured_angle - previous) / dt;
      state_.angle = measured_angle;
      return state_.velocity;
    }
    if (periods <= 1.0 + 1e-9) {
      euler_step(measured_angle, dt);  // the nominal tick
      return output();
    }
    const int substeps = static_cast<int>(periods - 1e-9) + 1;
    const double h = dt / substeps;
    for (int i = 1; i < substeps; ++i)
      euler_step(previous + (measured_angle - previous) * (static_cast<double>(i) / substeps), h);
    euler_step(measured_angle, h);
    return output();
  }

 private:
  static constexpr int kMaxSubsteps = 100;

  // theta' = w + kp e, w' = ki e with kp = 2 b, ki = b^2: error dynamics s^2 + 2bs + b^2.
  constexpr void euler_step(double target, double h) noexcept {
    const double b = config_.bandwidth_rad_s;
    const double error = target - state_.angle;
    state_.velocity += b * b * error * h;
    state_.rate = state_.velocity + 2.0 * b * error;
    state_.angle += state_.rate * h;
  }
  constexpr double output() const noexcept {
    return config_.method == VelocityMethod::tracking_loop_rate ? state_.rate : state_.velocity;
  }

  Config config_;
  State state_;
};

}  // namespace lever::fw
