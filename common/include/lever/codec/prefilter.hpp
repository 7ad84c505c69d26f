#pragma once
// First-order low-pass applied before the deadband decision (paper section III-E): extrapolation
// amplifies sensor noise, so the predictor sees a smoothed signal and the receiver gets smoothed values.
#include <cstddef>
#include <numbers>

#include "lever/common/vec.hpp"
#include "lever/math/elementary.hpp"

namespace lever::codec {

template <typename T, std::size_t N>
class LowPassPrefilter {
 public:
  explicit constexpr LowPassPrefilter(T cutoff_hz = T(0)) noexcept : cutoff_hz_(cutoff_hz) {}

  constexpr bool enabled() const noexcept { return cutoff_hz_ > T(0); }
  constexpr T cutoff_hz() const noexcept { return cutoff_hz_; }

  // The last output, what the deadband decided on (zero before the first sample).
  constexpr const Vec<T, N>& output() const noexcept { return y_; }

  // Forget the history: the next sample passes through unchanged (y_0 = x_0).
  constexpr void reset() noexcept { primed_ = false; }

  // y_k = y_{k-1} + alpha (x_k - y_{k-1}), alpha = 1 - exp(-2 pi f_c dt_k). The sample interval may vary.
  Vec<T, N> apply(T t, const Vec<T, N>& x) noexcept {
    if (!primed_) {
      primed_ = true;
      t_prev_ = t;
      y_ = x;
      return y_;
    }
    const T dt = t - t_prev_;
    t_prev_ = t;
    // exp() dominates the cost; at a fixed sample period dt repeats exactly, so alpha is reused.
    // Recomputing on any change keeps the result identical to evaluating the formula every time. lever::math's
    // exp, in double for float too: both ends of a link compute the same alpha whatever their libm.
    if (!(dt == cached_dt_)) {
      cached_dt_ = dt;
      alpha_ = T(1) - static_cast<T>(math::exp(static_cast<double>(-kTwoPi * cutoff_hz_ * dt)));
    }
    for (std::size_t i = 0; i < N; ++i) y_[i] = y_[i] + alpha_ * (x[i] - y_[i]);
    return y_;
  }

 private:
  static constexpr T kTwoPi = T(2) * std::numbers::pi_v<T>;
  T cutoff_hz_;
  bool primed_ = false;
  T t_prev_ = T(0);
  T cached_dt_ = T(-1);
  T alpha_ = T(0);
  Vec<T, N> y_{};
};

}  // namespace lever::codec
