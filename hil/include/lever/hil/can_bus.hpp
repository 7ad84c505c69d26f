#pragma once
// A classic CAN bus in simulated time: frames wait in their node's transmit queue, the bus arbitrates by id
// (lowest wins) whenever it goes idle, each frame occupies the bus for its worst-case stuffed length, and
// every other node receives it when its last bit is on the wire. Times are integer nanoseconds, so runs are
// exactly repeatable.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lever/protocol/can_frame.hpp"
#include "lever/protocol/can_timing.hpp"

namespace lever::hil {

using Nanos = std::int64_t;

using protocol::frame_bits_worst_case;

template <typename T, std::size_t N>
class Ring {
 public:
  bool push(const T& v) {
    if (size_ == N) return false;
    items_[(head_ + size_++) % N] = v;
    return true;
  }
  bool empty() const { return size_ == 0; }
  const T& front() const { return items_[head_]; }
  void pop() {
    head_ = (head_ + 1) % N;
    --size_;
  }
  std::size_t size() const { return size_; }

 private:
  std::array<T, N> items_{};
  std::size_t head_ = 0, size_ = 0;
};

struct TimedFrame {
  protocol::CanFrame frame;
  Nanos time = 0;  // ready (transmit queue) or delivered (receive queue)
};

class CanBus {
 public:
  using Node = std::size_t;
  struct NodeStats {
    std::uint64_t sent = 0, received = 0, tx_refused = 0, rx_overflow = 0;
  };

  explicit CanBus(double bitrate = 1e6) : ns_per_bit_(static_cast<Nanos>(1e9 / bitrate + 0.5)) {}
  // No bus at all: the memory of a controller that runs both levers. A frame takes no time, so it is delivered
  // when it is ready; ids still order frames ready together.
  static CanBus in_memory() {
    CanBus b;
    b.ns_per_bit_ = 0;
    return b;
  }

  Node add_node() {
    nodes_.emplace_back();
    return nodes_.size() - 1;
  }

  // Queue a frame that is ready at `ready`. Refused when the node's queue is full or it is bus-off.
  bool send(Node n, const protocol::CanFrame& f, Nanos ready) {
    auto& node = nodes_[n];
    if (node.bus_off || !node.tx.push({f, ready})) {
      ++node.stats.tx_refused;
      return false;
    }
    return true;
  }

  // The oldest frame delivered to this node by the current time.
  bool receive(Node n, protocol::CanFrame& f) {
    auto& rx = nodes_[n].rx;
    if (rx.empty() || rx.front().time > now_) return false;
    f = rx.front().frame;
    rx.pop();
    ++nodes_[n].stats.received;
    return true;
  }

  // The same, with the time the frame's last bit was on the wire.
  bool receive(Node n, TimedFrame& f) {
    auto& rx = nodes_[n].rx;
    if (rx.empty() || rx.front().time > now_) return false;
    f = rx.front();
    rx.pop();
    ++nodes_[n].stats.received;
    return true;
  }

  // Run the bus up to time t.
  void advance_to(Nanos t);

  // A node in bus-off neither sends nor receives; its queued frames are lost.
  void set_bus_off(Node n, bool off);

  // No frame waits to be sent and none is on the wire: nothing will be delivered until a node sends.
  bool idle() const {
    if (free_at_ > now_) return false;
    for (const auto& node : nodes_)
      if (!node.tx.empty()) return false;
    return true;
  }

  Nanos now() const { return now_; }
  double load() const { return now_ > 0 ? static_cast<double>(busy_) / static_cast<double>(now_) : 0.0; }
  std::uint64_t frames() const { return frames_; }
  const NodeStats& stats(Node n) const { return nodes_[n].stats; }

 private:
  struct NodeState {
    Ring<TimedFrame, 32> tx;
    Ring<TimedFrame, 128> rx;
    bool bus_off = false;
    NodeStats stats;
  };

  Nanos ns_per_bit_;
  std::vector<NodeState> nodes_;  // sized at set-up, never during a run
  Nanos now_ = 0;
  Nanos free_at_ = 0;  // when the bus goes idle
  Nanos busy_ = 0;
  std::uint64_t frames_ = 0;
};

}  // namespace lever::hil
