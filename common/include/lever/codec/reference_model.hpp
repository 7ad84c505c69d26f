#pragma once
// The model both ends of a link run on the transmitted samples. Sender and receiver each own one and feed
// it the same decoded values, so their references agree bit for bit while no frame is lost (section III-D).
#include <cstddef>
#include <cstdint>

#include "lever/codec/config.hpp"
#include "lever/common/vec.hpp"

namespace lever::codec {

template <typename T, std::size_t N>
struct TimedSample {
  T t{};
  Vec<T, N> v{};
};

template <typename T, std::size_t N>
class ReferenceModel {
 public:
  explicit constexpr ReferenceModel(Mode mode = Mode::deadband) noexcept : mode_(mode) {}

  constexpr Mode mode() const noexcept { return mode_; }
  // Switching mode keeps the transmitted history, so both ends stay coherent when they switch at the same
  // sample.
  constexpr void set_mode(Mode mode) noexcept { mode_ = mode; }
  constexpr void reset() noexcept { count_ = 0; }

  constexpr bool empty() const noexcept { return count_ == 0; }
  constexpr std::uint8_t samples_held() const noexcept { return count_; }
  constexpr const TimedSample<T, N>& newest() const noexcept { return a_; }

  constexpr void accept(T t, const Vec<T, N>& v) noexcept {
    b_ = a_;
    a_ = {t, v};
    if (count_ < 2) ++count_;
    // The slope only changes here; caching it keeps the per-sample path free of divisions while giving the
    // same bits as evaluating (v_a - v_b)/(t_a - t_b) every time.
    if (count_ == 2) {
      const T dt_ab = a_.t - b_.t;
      for (std::size_t i = 0; i < N; ++i) slope_[i] = (a_.v[i] - b_.v[i]) / dt_ab;
    }
  }

  // Reference at time t: v_a (zero-order hold), or v_a + (v_a - v_b)/(t_a - t_b) * (t - t_a).
  // Only meaningful when !empty(); an empty model answers zero.
  constexpr Vec<T, N> at(T t) const noexcept {
    if (mode_ == Mode::deadband || count_ < 2) return a_.v;
    Vec<T, N> out{};
    const T since_a = t - a_.t;
    for (std::size_t i = 0; i < N; ++i) out[i] = a_.v[i] + slope_[i] * since_a;
    return out;
  }

 private:
  Mode mode_;
  std::uint8_t count_ = 0;
  TimedSample<T, N> a_{};  // newest transmitted sample
  TimedSample<T, N> b_{};  // the one before it
  Vec<T, N> slope_{};
};

}  // namespace lever::codec
