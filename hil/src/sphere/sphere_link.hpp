#pragma once
// The sphere-3dof's LAN, one direction at a time: packets in datagrams over a NetworkLink, and at the receiver
// either each packet as it arrives, or a playout that hands each packet over once the receiver's clock reaches its
// sample time (SphereTopClock::op_playout).
#include <array>
#include <cstdint>

#include "lever/codec/sender.hpp"
#include "lever/hil/can_bus.hpp"
#include "lever/hil/network.hpp"
#include "lever/hil/sphere3dof.hpp"

namespace lever::hil {

// The link carries each packet's sequence number in a datagram; the payload waits in the sender's table, as
// the link model needs only the datagram's timing and fate.
template <typename Payload>
class PacketTable {
 public:
  protocol::CanFrame stamp(const Payload& p) {
    const std::uint32_t seq = next_++;
    items_[seq % items_.size()] = p;
    protocol::CanFrame f;
    f.dlc = 4;
    for (std::size_t i = 0; i < 4; ++i) f.data[i] = static_cast<std::uint8_t>(seq >> (8 * i));
    return f;
  }
  const Payload& at(const protocol::CanFrame& f) const {
    std::uint32_t seq = 0;
    for (std::size_t i = 0; i < 4; ++i) seq |= static_cast<std::uint32_t>(f.data[i]) << (8 * i);
    return items_[seq % items_.size()];
  }

 private:
  // The link holds at most 4096 datagrams, so no slot is reused while its datagram is in flight.
  std::array<Payload, 4096> items_{};
  std::uint32_t next_ = 0;
};

// Packets that have arrived wait here until the receiver's clock (now minus the link's nominal delay)
// reaches their sample time: the receiver then runs the sender's model exactly, that delay late.
template <typename Payload>
class Playout {
 public:
  bool push(const Payload& p) { return queue_.push(p); }
  template <typename Accept>
  void release(double until, Accept&& accept) {
    while (!queue_.empty() && queue_.front().t <= until) {
      accept(queue_.front());
      queue_.pop();
    }
  }

 private:
  Ring<Payload, 64> queue_;
};

// One direction of the link.
template <typename Payload>
class SphereChannel {
 public:
  SphereChannel(const NetworkParams& lan, std::uint64_t seed) : link_(lan, seed) {}

  void send(const Payload& p, Nanos t_ns) { link_.send(table_.stamp(p), t_ns); }
  // The datagrams arrived by t_ns wait in the playout (one older than the newest, or one the playout has no room
  // for, is stale: dropped, counted); then every packet whose sample time is `until` or earlier goes to
  // accept(packet).
  template <typename Accept>
  void receive(Nanos t_ns, double until, Accept&& accept) {
    receive_on_arrival(t_ns, [this](const Payload& p, Nanos) {
      if (!playout_.push(p)) ++stale_;
    });
    playout_.release(until, accept);
  }
  // Without a play-out: every datagram arrived by t_ns goes to accept(packet, arrival_ns) at once, in arrival order
  // (one older than the newest is stale: dropped, counted).
  template <typename Accept>
  void receive_on_arrival(Nanos t_ns, Accept&& accept) {
    TimedFrame arrived;
    while (link_.pop_arrived(t_ns, arrived)) {
      const Payload& p = table_.at(arrived.frame);
      if (p.t <= newest_t_) {
        ++stale_;
        continue;
      }
      newest_t_ = p.t;
      accept(p, arrived.time);
    }
  }
  std::uint64_t stale() const { return stale_; }

 private:
  NetworkLink link_;
  PacketTable<Payload> table_;
  Playout<Payload> playout_;
  double newest_t_ = -1.0;
  std::uint64_t stale_ = 0;
};

}  // namespace lever::hil
