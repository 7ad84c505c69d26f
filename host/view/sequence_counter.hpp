#pragma once
// Frames lost or out of order in a stream numbered modulo 256 (the data frames' seq, the heartbeats' counter).
// A jump forward by less than half the range is that many frames lost; anything behind the newest is a frame
// out of order (a duplicate among them). A late frame was counted lost when its successor came, and is counted
// again as out of order when it comes: the figures say what the bus did, not what a receiver recovered.
#include <cstdint>

namespace lever::view {

class SequenceCounter {
 public:
  void on(std::uint8_t seq) noexcept {
    if (!started_) {
      started_ = true;
      newest_ = seq;
      return;
    }
    const auto ahead = static_cast<std::uint8_t>(seq - newest_);
    if (ahead == 0 || ahead >= 128) {
      ++out_of_order_;
      return;
    }
    lost_ += ahead - 1u;
    newest_ = seq;
  }
  // A new stream (its sender restarted): nothing before it counts against the next number.
  void restart() noexcept { started_ = false; }
  void reset() noexcept { *this = SequenceCounter{}; }

  std::uint64_t lost() const noexcept { return lost_; }
  std::uint64_t out_of_order() const noexcept { return out_of_order_; }

 private:
  bool started_ = false;
  std::uint8_t newest_ = 0;
  std::uint64_t lost_ = 0;
  std::uint64_t out_of_order_ = 0;
};

}  // namespace lever::view
