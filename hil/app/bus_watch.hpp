#pragma once
// What `lever-hil serve` sees on the levers' CAN buses, as a logic analyser would: each lever's state from
// its heartbeats, and the data frames at each site. It never sends. The world needs it to know when the pair
// is armed (the operator takes the handle then) and to report packet rates and the force the HSI displays.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lever/board/result.hpp"
#include "lever/board/socketcan.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::hil {

struct WatchedLever {
  std::optional<protocol::HeartbeatMessage> heartbeat;  // the newest one, none before the first
  std::int64_t heartbeat_at_ms = 0;                     // the watch's clock
  bool armed() const { return heartbeat && heartbeat->state == protocol::LeverState::armed; }
};

class BusWatch {
 public:
  // The HSI's and the TOP's interfaces (the same one when both levers are at one site), and their pair.
  static board::Result<BusWatch> open(const std::string& hsi_interface, const std::string& top_interface,
                                      std::uint8_t pair);

  // Reads every frame that has arrived; `now_ms` stamps the heartbeats.
  void poll(std::int64_t now_ms);

  // A lever whose heartbeat is older than this is silent: killed, rebooting, or its bus cut.
  const WatchedLever& hsi() const { return levers_[0]; }
  const WatchedLever& top() const { return levers_[1]; }
  bool heard_within(const WatchedLever& lever, std::int64_t now_ms, std::int64_t window_ms) const {
    return lever.heartbeat && now_ms - lever.heartbeat_at_ms <= window_ms;
  }

  // Data frames as sent: motion on the HSI's bus, force on the TOP's. Counted since the last take.
  std::uint64_t take_motion_frames() { return std::exchange(motion_frames_, 0); }
  std::uint64_t take_force_frames() { return std::exchange(force_frames_, 0); }
  // The newest force as it reached the HSI's bus (N): what a deadband receiver displays. None before the first.
  std::optional<double> force_at_hsi() const { return force_at_hsi_; }
  // The newest position the HSI sent (rad): the TOP's reference.
  std::optional<double> position_sent() const { return position_sent_; }
  std::uint64_t frames_read() const { return frames_read_; }

 private:
  BusWatch(std::vector<board::SocketCan> sockets, bool one_site, std::uint8_t pair)
      : sockets_(std::move(sockets)), one_site_(one_site), pair_(pair) {}
  void take(const protocol::CanFrame& f, bool hsi_site, bool top_site, std::int64_t now_ms);

  std::vector<board::SocketCan> sockets_;  // [0] the HSI's site, [1] the TOP's unless one_site_
  bool one_site_;
  std::uint8_t pair_;
  std::array<WatchedLever, 2> levers_{};
  std::uint64_t motion_frames_ = 0, force_frames_ = 0, frames_read_ = 0;
  std::optional<double> force_at_hsi_, position_sent_;
};

}  // namespace lever::hil
