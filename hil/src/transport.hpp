#pragma once
// The transport between the levers as lever-hil run models it: one CAN bus per site joined by two lever-bridges
// over a simulated IP link, one bus for both levers, or none: both levers in one controller, frames in memory.
#include <optional>

#include "lever/hil/can_bus.hpp"
#include "lever/hil/network.hpp"
#include "lever/hil/simulation.hpp"

namespace lever::hil {

// A lever-bridge: every lever-protocol frame on its bus goes to the link, every datagram from the link onto
// its bus, each `latency` after it was received, by its own timestamp.
struct Bridge {
  CanBus* bus;
  CanBus::Node node;
  NetworkLink* outgoing;
  NetworkLink* incoming;
  Nanos latency;

  void pump(Nanos now);
};

class Transport {
 public:
  // The buses and the links; the bridges join them once every lever and the host have their node (add_bridges).
  explicit Transport(const SimConfig& config);
  Transport(const Transport&) = delete;  // the bridges and the levers' HALs point into it
  Transport& operator=(const Transport&) = delete;

  void add_bridges();
  // The frames of the tick that ends at `now`, each at its own time.
  void step(Nanos now);
  // One controller: the frames the levers sampled at `now` reach each other before they act.
  void hand_over(Nanos now) { hsi_bus_.advance_to(now); }
  void finish(SimResult& result) const;

  CanBus& hsi_bus() { return hsi_bus_; }
  CanBus& top_bus() { return one_bus_ ? hsi_bus_ : top_site_bus_; }
  NetworkLink& to_top() { return to_top_; }
  NetworkLink& to_hsi() { return to_hsi_; }

 private:
  void service(Nanos from, Nanos now);
  bool quiet(Nanos now) const;

  bool one_bus_;  // one controller's memory or one site's bus: both levers on hsi_bus_, no bridges
  Nanos latency_;
  // Serviced every step_: a frame a bridge picks up in (s - step, s] is queued at s with its own time + latency > s,
  // ahead of where the bus has run, so with step <= latency every frame's delay is exactly what the bus and network
  // models give it (servicing only at ticks added up to two ticks to each hop: a frame took 3 ticks from one lever
  // to the other).
  Nanos step_;
  CanBus hsi_bus_, top_site_bus_;
  NetworkLink to_top_, to_hsi_;
  std::optional<Bridge> bridges_[2];  // at the HSI's site, at the TOP's; none on one site
};

}  // namespace lever::hil
