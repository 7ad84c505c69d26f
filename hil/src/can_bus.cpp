#include "lever/hil/can_bus.hpp"

#include <limits>

namespace lever::hil {

void CanBus::advance_to(Nanos t) {
  while (true) {
    if (free_at_ < now_) free_at_ = now_;
    // Arbitration at the moment the bus goes idle: among frames ready by then, the lowest id wins.
    Node winner = nodes_.size();
    Nanos earliest_ready = std::numeric_limits<Nanos>::max();
    for (Node n = 0; n < nodes_.size(); ++n) {
      const auto& tx = nodes_[n].tx;
      if (tx.empty()) continue;
      const auto& head = tx.front();
      if (head.time <= free_at_) {
        if (winner == nodes_.size() || head.frame.id < nodes_[winner].tx.front().frame.id) winner = n;
      } else if (head.time < earliest_ready) {
        earliest_ready = head.time;
      }
    }
    if (winner == nodes_.size()) {
      if (earliest_ready > t) break;
      free_at_ = earliest_ready;  // idle until the next frame is ready
      continue;
    }
    if (free_at_ > t) break;
    const auto frame = nodes_[winner].tx.front().frame;
    nodes_[winner].tx.pop();
    const Nanos duration = frame_bits_worst_case(frame.dlc > 8 ? 8 : frame.dlc) * ns_per_bit_;
    const Nanos done = free_at_ + duration;
    busy_ += duration;
    free_at_ = done;
    ++frames_;
    ++nodes_[winner].stats.sent;
    for (Node n = 0; n < nodes_.size(); ++n) {
      if (n == winner || nodes_[n].bus_off) continue;
      if (!nodes_[n].rx.push({frame, done})) ++nodes_[n].stats.rx_overflow;
    }
  }
  now_ = t;
}

void CanBus::set_bus_off(Node n, bool off) {
  auto& node = nodes_[n];
  node.bus_off = off;
  if (off) {
    while (!node.tx.empty()) node.tx.pop();
    while (!node.rx.empty()) node.rx.pop();
  }
}

}  // namespace lever::hil
