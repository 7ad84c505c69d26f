#include "lever/hil/network.hpp"

#include <algorithm>

namespace lever::hil {

void NetworkLink::send(const protocol::CanFrame& f, Nanos t) {
  ++stats_.sent;
  const std::uint64_t order = next_order_++;
  // Draw both numbers for every datagram so a change of loss does not shift the jitter sequence.
  const double jitter = rng_.uniform() * p_.jitter_ms;
  const double draw = rng_.uniform();
  const bool lost = draw < p_.loss || draw < burst_loss_;
  if (down_ || lost) {
    ++stats_.lost;
    return;
  }
  Nanos arrival = t + static_cast<Nanos>((p_.delay_ms + extra_delay_ms_ + jitter) * 1e6);
  if (!p_.reorder && arrival < last_arrival_) arrival = last_arrival_;
  last_arrival_ = std::max(last_arrival_, arrival);
  if (size_ == heap_.size()) {
    ++stats_.overflow;
    return;
  }
  heap_[size_++] = {arrival, order, f};
  std::push_heap(heap_.begin(), heap_.begin() + static_cast<std::ptrdiff_t>(size_), later);
}

bool NetworkLink::pop_arrived(Nanos t, TimedFrame& f) {
  if (size_ == 0 || heap_[0].arrival > t) return false;
  std::pop_heap(heap_.begin(), heap_.begin() + static_cast<std::ptrdiff_t>(size_), later);
  const InFlight& d = heap_[--size_];
  if (delivered_any_ && d.order < delivered_order_max_) ++stats_.reordered;
  delivered_order_max_ = std::max(delivered_order_max_, d.order);
  delivered_any_ = true;
  ++stats_.delivered;
  f = {d.frame, d.arrival};
  return true;
}

}  // namespace lever::hil
