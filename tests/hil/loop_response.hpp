#pragma once
// The levers' control loops in the frequency domain, from the firmware's own gains and the HIL's documented
// plant (docs/hil-model.md): what the timing budget of firmware/core is derived from (docs/firmware.md,
// "Timing budget"). Sampled-data and exact at the samples: the plant is discretized for the 1 ms zero-order
// hold by its matrix exponential, the velocity estimator is the firmware's own Euler recursion, delays of whole
// ticks are z^-n. What is not sampled (the strain-gauge amplifier's filter and output hold) is continuous.
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <vector>

#include "lever/fw/velocity_estimator.hpp"

namespace lever::test {

using Complex = std::complex<double>;
inline constexpr double kPeriod = 1e-3;  // s, the firmware's tick

// One lever's mechanics with its motor: states (motor torque, angle, speed); input the commanded torque.
struct LeverMechanics {
  double inertia = 0.0;      // kg m^2
  double damping = 0.0;      // N m s/rad: viscous friction, plus a hand's or a wall's
  double stiffness = 0.0;    // N m/rad: a hand's or a wall's
  double motor_lag_s = 0.0;  // the current loop as a first-order lag
};

// The zero-order-hold discretization of LeverMechanics at kPeriod, and its pulse transfer function from the
// commanded torque to the angle.
class SampledPlant {
 public:
  explicit SampledPlant(const LeverMechanics& m) {
    // Augmented [A B; 0 0] * T, whose exponential holds Ad and Bd.
    using M4 = std::array<std::array<double, 4>, 4>;
    M4 a{};
    a[0][0] = -1.0 / m.motor_lag_s;
    a[0][3] = 1.0 / m.motor_lag_s;
    a[1][2] = 1.0;
    a[2][0] = 1.0 / m.inertia;
    a[2][1] = -m.stiffness / m.inertia;
    a[2][2] = -m.damping / m.inertia;
    for (auto& row : a)
      for (auto& v : row) v *= kPeriod;
    const M4 e = expm(a);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) ad_[i][j] = e[i][j];
      bd_[i] = e[i][3];
    }
  }

  // Angle over commanded torque at z.
  Complex at(Complex z) const {
    std::array<std::array<Complex, 4>, 3> m{};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[i][j] = (i == j ? z : Complex{0.0}) - ad_[i][j];
      m[i][3] = bd_[i];
    }
    for (int c = 0; c < 3; ++c) {  // Gauss-Jordan with partial pivoting
      int p = c;
      for (int r = c + 1; r < 3; ++r)
        if (std::abs(m[r][c]) > std::abs(m[p][c])) p = r;
      std::swap(m[c], m[p]);
      for (int r = 0; r < 3; ++r) {
        if (r == c) continue;
        const Complex f = m[r][c] / m[c][c];
        for (int k = c; k < 4; ++k) m[r][k] -= f * m[c][k];
      }
    }
    return m[1][3] / m[1][1];
  }

  const std::array<std::array<double, 3>, 3>& ad() const { return ad_; }
  const std::array<double, 3>& bd() const { return bd_; }

 private:
  template <typename M>
  static M multiply(const M& x, const M& y) {
    M r{};
    for (std::size_t i = 0; i < x.size(); ++i)
      for (std::size_t j = 0; j < x.size(); ++j)
        for (std::size_t k = 0; k < x.size(); ++k) r[i][j] += x[i][k] * y[k][j];
    return r;
  }
  // Scaling and squaring with a Taylor series: plenty for a 4 x 4 of norm below a few.
  template <typename M>
  static M expm(M a) {
    int squarings = 0;
    double norm = 0.0;
    for (const auto& row : a) {
      double s = 0.0;
      for (const double v : row) s += std::fabs(v);
      norm = std::max(norm, s);
    }
    while (norm > 0.5) {
      norm /= 2.0;
      ++squarings;
    }
    for (auto& row : a)
      for (auto& v : row) v = std::ldexp(v, -squarings);
    M e{}, term{};
    for (std::size_t i = 0; i < a.size(); ++i) e[i][i] = term[i][i] = 1.0;
    for (int k = 1; k < 20; ++k) {
      term = multiply(term, a);
      for (auto& row : term)
        for (auto& v : row) v /= k;
      for (std::size_t i = 0; i < a.size(); ++i)
        for (std::size_t j = 0; j < a.size(); ++j) e[i][j] += term[i][j];
    }
    for (int i = 0; i < squarings; ++i) e = multiply(e, e);
    return e;
  }

  std::array<std::array<double, 3>, 3> ad_{};
  std::array<double, 3> bd_{};
};

// The firmware's velocity estimate over the angle (VelocityEstimator: one Euler step per tick,
// v_k = v_{k-1} + b^2 h e_k, a_k = a_{k-1} + h (v_k + 2 b e_k), e_k = theta_k - a_{k-1}); its output is the
// integrator v (tracking_loop) or the angle estimate's rate v + 2 b e (tracking_loop_rate).
inline Complex velocity_estimate(Complex z, const fw::VelocityEstimator::Config& config) {
  const double h = kPeriod, b = config.bandwidth_rad_s;
  const Complex q = 1.0 - 1.0 / z;
  if (config.method == fw::VelocityMethod::backward_difference) return q / h;
  const Complex g = b * b * h * h / (q * q) + 2.0 * b * h / q;  // a = g e
  const Complex e = 1.0 / (1.0 + g / z);                        // e = theta - a / z
  const Complex integrator = b * b * h / q * e;
  return config.method == fw::VelocityMethod::tracking_loop_rate ? integrator + 2.0 * b * e : integrator;
}

// The output's gain for white noise on the angle, sqrt((1/pi) integral over 0..pi of |H|^2): what a moving encoder's
// quantization (uniform, white at 1 kHz) becomes in the estimate, per radian of its standard deviation.
// `response` maps z to the output over the angle.
template <typename Response>
double white_noise_gain(const Response& response) {
  constexpr int kSteps = 20000;
  double sum = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double w = std::numbers::pi * (i + 0.5) / kSteps;
    sum += std::norm(response(std::polar(1.0, w)));
  }
  return std::sqrt(sum / kSteps);
}
inline double white_noise_gain(const fw::VelocityEstimator::Config& config) {
  return white_noise_gain([&](Complex z) { return velocity_estimate(z, config); });
}

struct Margin {
  double crossover_hz = 0.0;
  double phase_margin_deg = 0.0;
  // What a delay costs at the crossover, and the delay that uses the whole margin.
  double degrees_per_ms() const { return 360.0 * crossover_hz * 1e-3; }
  double delay_margin_ms() const { return phase_margin_deg / degrees_per_ms(); }
};

// The crossover with the smallest phase margin of an open loop L(omega) (negative feedback: 1 + L), searched
// below the Nyquist frequency; none when |L| never crosses 1. The phase is unwrapped from 1 rad/s up, starting in
// (-270, 90] degrees (a double integrator starts at -180, a spring with a damper's lead just above 0), so that a
// crossing with a phase lead reads as the wide margin it is, not as a lag of nearly 360 degrees.
template <typename Loop>
std::optional<Margin> smallest_margin(const Loop& loop) {
  std::optional<Margin> worst;
  const double top = std::numbers::pi / kPeriod;
  const auto wrapped = [](double a) { return std::remainder(a, 2.0 * std::numbers::pi); };
  double w0 = 1.0;
  Complex l0 = loop(w0);
  double phase0 = std::arg(l0);
  if (phase0 > std::numbers::pi / 2.0) phase0 -= 2.0 * std::numbers::pi;
  for (double w1 = w0 * 1.001; w1 < top; w0 = w1, w1 *= 1.001) {
    const Complex l1 = loop(w1);
    const double phase1 = phase0 + wrapped(std::arg(l1) - std::arg(l0));
    if ((std::abs(l0) - 1.0) * (std::abs(l1) - 1.0) < 0.0) {
      double lo = w0, hi = w1;  // bisect |L| = 1
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        ((std::abs(loop(lo)) - 1.0) * (std::abs(loop(mid)) - 1.0) <= 0.0 ? hi : lo) = mid;
      }
      const double w = 0.5 * (lo + hi);
      const double phase = phase0 + wrapped(std::arg(loop(w)) - std::arg(l0));
      const Margin m{w / (2.0 * std::numbers::pi), (std::numbers::pi + phase) * 180.0 / std::numbers::pi};
      if (!worst || m.phase_margin_deg < worst->phase_margin_deg) worst = m;
    }
    l0 = l1;
    phase0 = phase1;
  }
  return worst;
}

}  // namespace lever::test
