#include "transport.hpp"

#include <algorithm>

#include "lever/protocol/messages.hpp"

namespace lever::hil {
namespace {
constexpr Nanos kTick = 1'000'000;
}

void Bridge::pump(Nanos now) {
  TimedFrame tf;
  while (incoming->pop_arrived(now, tf)) bus->send(node, tf.frame, tf.time + latency);
  protocol::FrameAddress address;
  while (bus->receive(node, tf))
    if (protocol::classify(tf.frame.id, address) == protocol::DecodeError::none)
      outgoing->send(tf.frame, tf.time + latency);
}

Transport::Transport(const SimConfig& config)
    : one_bus_(config.topology != Topology::two_sites),
      latency_(static_cast<Nanos>(config.bridge_latency_us * 1e3)),
      step_(std::min<Nanos>(latency_, 100'000)),
      hsi_bus_(config.topology == Topology::one_controller ? CanBus::in_memory() : CanBus(config.bitrate)),
      top_site_bus_(config.bitrate),
      to_top_(config.network, config.seed * 4 + 1),
      to_hsi_(config.network, config.seed * 4 + 2) {}

void Transport::add_bridges() {
  if (one_bus_) return;
  bridges_[0].emplace(Bridge{&hsi_bus_, hsi_bus_.add_node(), &to_top_, &to_hsi_, latency_});
  bridges_[1].emplace(Bridge{&top_site_bus_, top_site_bus_.add_node(), &to_hsi_, &to_top_, latency_});
}

void Transport::step(Nanos now) { service(now - kTick, now); }

void Transport::service(Nanos from, Nanos now) {
  for (Nanos s = from + step_;; s += step_) {
    if (s > now || quiet(now)) s = now;  // nothing on the buses, nothing arriving: nothing to do before now
    hsi_bus_.advance_to(s);
    if (!one_bus_) top_site_bus_.advance_to(s);
    for (auto& b : bridges_)
      if (b) b->pump(s);
    if (s == now) break;
  }
}

bool Transport::quiet(Nanos now) const {
  if (!hsi_bus_.idle() || !(one_bus_ ? hsi_bus_ : top_site_bus_).idle()) return false;
  for (const auto& b : bridges_)
    if (b && b->incoming->arrives_by(now)) return false;
  return true;
}

void Transport::finish(SimResult& result) const {
  result.bus_load_hsi = hsi_bus_.load();
  result.bus_load_top = one_bus_ ? hsi_bus_.load() : top_site_bus_.load();
  result.network_sent = to_top_.stats().sent + to_hsi_.stats().sent;
  result.network_lost = to_top_.stats().lost + to_hsi_.stats().lost;
  result.network_reordered = to_top_.stats().reordered + to_hsi_.stats().reordered;
}

}  // namespace lever::hil
