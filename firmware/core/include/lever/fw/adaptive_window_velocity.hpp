#pragma once
// Velocity as the adaptive-window difference of the encoder's count (end-fit first-order adaptive windowing:
// Janabi-Sharifi, Hayward and Chen, "Discrete-time adaptive windowing for velocity estimation", IEEE Trans. Control
// Systems Technology 8(6), 2000). Each tick it takes the longest window, up to max_window ticks, over which the
// straight line through the newest count and the count n samples older passes within bound_counts of every count
// between them, and returns that line's slope. Still a time difference of the quantized position (the paper's III-E),
// but long while the lever moves slowly (fine steps) and short when it accelerates. Integer counts and ticks, so the
// test is exact; at rest every window is flat and the velocity exactly zero. No heap: a fixed ring of samples.
#include <cstddef>
#include <cstdint>

#include "lever/fw/tick.hpp"

namespace lever::fw {

class AdaptiveWindowVelocity {
 public:
  static constexpr std::size_t kCapacity = 32;  // samples kept: a window of up to 31 ticks
  struct Config {
    Tick max_window = 20;           // ticks (20 ms)
    std::int64_t bound_counts = 1;  // d: the quantization error's bound, one count
  };

  constexpr AdaptiveWindowVelocity() noexcept : AdaptiveWindowVelocity(Config{}) {}
  explicit constexpr AdaptiveWindowVelocity(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  // The window the last update used, in ticks (0 before the second sample).
  constexpr Tick window() const noexcept { return window_; }

  // The count at tick `now` (later than the last); returns the velocity in counts per tick.
  constexpr double update(std::int64_t count, Tick now) noexcept {
    head_ = (head_ + 1) % kCapacity;
    samples_[head_] = {count, now};
    if (size_ < kCapacity) ++size_;
    window_ = 0;
    if (size_ < 2) return 0.0;
    const Sample& newest = samples_[head_];
    std::int64_t rise = newest.count - at(1).count;
    Tick run = newest.tick - at(1).tick;
    for (std::size_t n = 2; n < size_; ++n) {
      const Sample& oldest = at(n);
      const Tick span = newest.tick - oldest.tick;
      if (span > config_.max_window) break;
      const std::int64_t dy = newest.count - oldest.count;
      if (!fits(n, dy, span)) break;  // the first window that fails ends the search
      rise = dy;
      run = span;
    }
    window_ = run;
    return run > 0 ? static_cast<double>(rise) / static_cast<double>(run) : 0.0;
  }

  constexpr void reset() noexcept { size_ = 0; }

 private:
  struct Sample {
    std::int64_t count = 0;
    Tick tick = 0;
  };

  constexpr const Sample& at(std::size_t back) const noexcept {
    return samples_[(head_ + kCapacity - back) % kCapacity];
  }

  // Every count between the newest and the one n samples back within the bound of the line through both:
  // |y_j - y_k + dy (t_k - t_j) / span| <= d, multiplied through by span.
  constexpr bool fits(std::size_t n, std::int64_t dy, Tick span) const noexcept {
    const Sample& newest = samples_[head_];
    const auto s = static_cast<std::int64_t>(span);
    for (std::size_t j = 1; j < n; ++j) {
      const Sample& mid = at(j);
      const std::int64_t off = (mid.count - newest.count) * s + dy * static_cast<std::int64_t>(newest.tick - mid.tick);
      if (off > config_.bound_counts * s || off < -config_.bound_counts * s) return false;
    }
    return true;
  }

  Config config_;
  Sample samples_[kCapacity]{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  Tick window_ = 0;
};

constexpr bool is_valid(const AdaptiveWindowVelocity::Config& c) noexcept {
  return c.max_window >= 1 && c.max_window < AdaptiveWindowVelocity::kCapacity && c.bound_counts >= 0;
}

}  // namespace lever::fw
