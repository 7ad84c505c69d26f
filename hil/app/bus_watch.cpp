#include "bus_watch.hpp"

#include <utility>

namespace lever::hil {

board::Result<BusWatch> BusWatch::open(const std::string& hsi_interface, const std::string& top_interface,
                                       std::uint8_t pair) {
  std::vector<board::SocketCan> sockets;
  const bool one_site = hsi_interface == top_interface;
  for (const auto& name : one_site ? std::vector{hsi_interface} : std::vector{hsi_interface, top_interface}) {
    auto s = board::SocketCan::open({name, {}, 0, false});
    if (!s) return s.error();
    sockets.push_back(std::move(s).value());
  }
  return BusWatch(std::move(sockets), one_site, pair);
}

void BusWatch::poll(std::int64_t now_ms) {
  for (std::size_t i = 0; i < sockets_.size(); ++i) {
    protocol::CanFrame f;
    std::int64_t stamp = 0;
    for (int n = 0; n < 1000 && sockets_[i].read(f, stamp) == board::IoStatus::ok; ++n)
      take(f, i == 0, one_site_ || i == 1, now_ms);
  }
}

void BusWatch::take(const protocol::CanFrame& f, bool hsi_site, bool top_site, std::int64_t now_ms) {
  ++frames_read_;
  protocol::FrameAddress address;
  if (protocol::classify(f.id, address) != protocol::DecodeError::none || address.pair != pair_) return;
  switch (address.kind) {
    case protocol::MessageKind::heartbeat: {
      protocol::HeartbeatMessage m;
      // A lever's own site hears it first; over a bridge the same heartbeat comes again, later.
      const bool own_site = address.role == protocol::Role::hsi ? hsi_site : top_site;
      if (own_site && protocol::decode(f, m, address) == protocol::DecodeError::none) {
        auto& lever = levers_[address.role == protocol::Role::hsi ? 0 : 1];
        lever.heartbeat = m;
        lever.heartbeat_at_ms = now_ms;
      }
      break;
    }
    case protocol::MessageKind::motion: {
      protocol::MotionMessage m;
      if (hsi_site && protocol::decode(f, m, address) == protocol::DecodeError::none) {
        ++motion_frames_;
        position_sent_ = m.position * protocol::kPositionLsbRad;
      }
      break;
    }
    case protocol::MessageKind::force: {
      protocol::ForceMessage m;
      if (protocol::decode(f, m, address) != protocol::DecodeError::none) break;
      if (top_site) ++force_frames_;
      if (hsi_site) force_at_hsi_ = m.force * protocol::kForceLsb;
      break;
    }
    case protocol::MessageKind::command:
    case protocol::MessageKind::energy:
    case protocol::MessageKind::settings:
      break;
  }
}

}  // namespace lever::hil
