#pragma once
// An incremental encoder as the firmware sees it: A/B level changes, one per count, queued between ticks
// like libgpiod edge events. Glitches (both lines flipping at once) can be injected.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>

#include "lever/fw/quadrature_decoder.hpp"

namespace lever::hil {

class QuadratureEncoder {
 public:
  explicit QuadratureEncoder(double counts_per_rev = 16384.0, double angle = 0.0)
      : counts_per_radian_(counts_per_rev / (2.0 * std::numbers::pi)), count_(count_at(angle)) {}

  // The lever moved to `angle`: one edge per count crossed, in order.
  void track(double angle) {
    const std::int64_t target = count_at(angle);
    while (count_ != target) {
      count_ += target > count_ ? 1 : -1;
      push(levels_of(count_));
    }
  }

  // A spurious transition to the diagonal state and back: two illegal transitions for the decoder.
  void glitch() {
    push(levels_of(count_ + 2));
    push(levels_of(count_));
  }

  fw::AbState levels() const { return levels_of(count_); }
  std::int64_t count() const { return count_; }
  std::uint64_t overflowed() const { return overflowed_; }

  // EdgeEncoderPort
  std::size_t drain_edges(fw::AbState* out, std::size_t capacity) {
    std::size_t n = 0;
    while (n < capacity && size_ > 0) {
      out[n++] = edges_[head_];
      head_ = (head_ + 1) % edges_.size();
      --size_;
    }
    return n;
  }

 private:
  // Gray sequence 00, 01, 11, 10 in (A<<1)|B coding.
  static fw::AbState levels_of(std::int64_t count) {
    constexpr fw::AbState kGray[4] = {0b00, 0b01, 0b11, 0b10};
    return kGray[((count % 4) + 4) % 4];
  }
  std::int64_t count_at(double angle) const {
    return static_cast<std::int64_t>(std::floor(angle * counts_per_radian_));
  }
  void push(fw::AbState s) {
    if (size_ == edges_.size()) {
      ++overflowed_;  // as a kernel's event FIFO would: the oldest edges are kept, the newest lost
      return;
    }
    edges_[(head_ + size_++) % edges_.size()] = s;
  }

  double counts_per_radian_;
  std::int64_t count_;
  std::array<fw::AbState, 1024> edges_{};
  std::size_t head_ = 0, size_ = 0;
  std::uint64_t overflowed_ = 0;
};

}  // namespace lever::hil
