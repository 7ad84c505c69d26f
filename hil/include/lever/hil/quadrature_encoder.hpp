#pragma once
// An incremental encoder as the firmware sees it: A/B level changes, one per count, queued between ticks
// like libgpiod edge events, with an index (Z) pulse once a turn at count 0. The queue is bounded like a
// kernel's event FIFO: when it overflows the newest edges are lost, and the next drain says so, as a source
// with sequence numbers would. Glitches (both lines flipping at once) can be injected.
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
      : counts_per_rev_(static_cast<std::int64_t>(counts_per_rev)),
        counts_per_radian_(counts_per_rev / (2.0 * std::numbers::pi)),
        count_(count_at(angle)) {}

  // The lever moved to `angle`: one edge per count crossed, in order.
  void track(double angle) {
    const std::int64_t target = count_at(angle);
    while (count_ != target) {
      count_ += target > count_ ? 1 : -1;
      push({levels_of(count_), count_ % counts_per_rev_ == 0});
    }
  }

  // A spurious transition to the diagonal state and back: two illegal transitions for the decoder.
  void glitch() {
    push({levels_of(count_ + 2), false});
    push({levels_of(count_), false});
  }

  fw::AbState levels() const { return levels_of(count_); }
  std::int64_t count() const { return count_; }
  std::uint64_t overflowed() const { return overflowed_; }
  // The queue's depth, at most its full size: smaller for fault injection (a v1 libgpiod line holds 16 events),
  // full for an encoder read by a hardware counter, which has no queue (EncoderInterface::counter).
  void set_queue_capacity(std::size_t capacity) { capacity_ = capacity < edges_.size() ? capacity : edges_.size(); }
  static constexpr std::size_t kMaxQueue = 1024;

  // EdgeEncoderPort
  fw::EdgeDrain drain_edges(fw::EncoderEdge* out, std::size_t capacity) {
    fw::EdgeDrain d;
    while (d.count < capacity && size_ > 0) {
      out[d.count++] = edges_[head_];
      head_ = (head_ + 1) % edges_.size();
      --size_;
    }
    // Reported with the drain that reaches the gap: the edges before it are good, the count after it is not.
    if (size_ == 0 && unreported_lost_ > 0) {
      d.lost = static_cast<std::uint32_t>(unreported_lost_ > UINT32_MAX ? UINT32_MAX : unreported_lost_);
      unreported_lost_ = 0;
    }
    return d;
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
  void push(fw::EncoderEdge e) {
    if (size_ >= capacity_) {
      ++overflowed_;  // as a kernel's event FIFO would: the oldest edges are kept, the newest lost
      ++unreported_lost_;
      return;
    }
    edges_[(head_ + size_++) % edges_.size()] = e;
  }

  std::int64_t counts_per_rev_;
  double counts_per_radian_;
  std::int64_t count_;
  std::array<fw::EncoderEdge, kMaxQueue> edges_{};
  std::size_t capacity_ = 32;  // libgpiod's v1 interface keeps 16 events per line: A and B
  std::uint64_t unreported_lost_ = 0;
  std::size_t head_ = 0, size_ = 0;
  std::uint64_t overflowed_ = 0;
};

}  // namespace lever::hil
