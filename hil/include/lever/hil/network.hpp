#pragma once
// One direction of the IP link between the two sites' bridges: delay, jitter, random and burst loss, and
// reordering, all seeded. Each CAN frame travels in its own datagram, as lever-bridge sends them.
#include <array>
#include <cstdint>

#include "lever/common/rng.hpp"
#include "lever/hil/can_bus.hpp"

namespace lever::hil {

struct NetworkParams {
  double delay_ms = 0.0;   // one way
  double jitter_ms = 0.0;  // uniform in [0, jitter] added to each datagram
  double loss = 0.0;       // probability a datagram is lost
  bool reorder = true;     // false: a datagram never overtakes an earlier one (a FIFO link)
};

class NetworkLink {
 public:
  struct Stats {
    std::uint64_t sent = 0, lost = 0, delivered = 0, reordered = 0, overflow = 0;
  };

  NetworkLink(const NetworkParams& p, std::uint64_t seed) : p_(p), rng_(seed) {}

  void send(const protocol::CanFrame& f, Nanos t);
  // The next datagram that has arrived by t, in arrival order, with its arrival time.
  bool pop_arrived(Nanos t, TimedFrame& f);

  // Fault injection.
  void set_down(bool down) { down_ = down; }  // every datagram lost
  void set_extra_delay_ms(double ms) { extra_delay_ms_ = ms; }
  void set_burst_loss(double loss) { burst_loss_ = loss; }  // on top of the base loss

  // Some datagram arrives by t.
  bool arrives_by(Nanos t) const { return size_ > 0 && heap_[0].arrival <= t; }
  const Stats& stats() const { return stats_; }

 private:
  struct InFlight {
    Nanos arrival;
    std::uint64_t order;  // send order, breaks ties and detects reordering
    protocol::CanFrame frame;
  };
  static bool later(const InFlight& a, const InFlight& b) {
    return a.arrival != b.arrival ? a.arrival > b.arrival : a.order > b.order;
  }

  NetworkParams p_;
  Rng rng_;
  bool down_ = false;
  double extra_delay_ms_ = 0.0;
  double burst_loss_ = 0.0;
  std::array<InFlight, 4096> heap_{};
  std::size_t size_ = 0;
  std::uint64_t next_order_ = 0;
  std::uint64_t delivered_order_max_ = 0;
  bool delivered_any_ = false;
  Nanos last_arrival_ = 0;
  Stats stats_;
};

}  // namespace lever::hil
