#pragma once
// The bridge's single-threaded relay: CAN frames out as authenticated datagrams at once, authentic and allowed
// datagrams back onto the bus, probes for round trip and clock offset, stats, and a recorder fed off the path.
#include <cstdint>
#include <memory>
#include <optional>

#include "bridge_config.hpp"
#include "bridge_stats.hpp"
#include "candump_recorder.hpp"
#include "datagram.hpp"
#include "lever/platform/socketcan.hpp"
#include "lever/platform/udp_socket.hpp"
#include "lever/platform/unique_fd.hpp"
#include "peer_session.hpp"

namespace lever::bridge {

class Relay {
 public:
  // Everything that can fail at start-up fails here, with a message: returns false and sets `error`.
  bool start(const BridgeConfig& config, const Key& key, std::string& error);
  // Runs until SIGINT, SIGTERM or SIGHUP (blocked in every thread before start()). Returns the exit code.
  int run();

  const BridgeCounters& counters() const { return counters_; }

 private:
  void relay_can_to_network();
  void relay_network_to_can();
  void handle_data(const Datagram& d, std::int64_t arrival_us);
  void on_timer();
  bool send(Datagram& d);
  void print_stats(double interval_s);
  void check_can();
  void send_probe();

  BridgeConfig config_;
  Key key_{};
  std::uint8_t site_id_ = 0;
  std::optional<platform::SocketCan> can_;  // opened by start()
  std::optional<platform::UdpSocket> udp_;  // opened by start()
  platform::SocketAddress peer_;
  platform::UniqueFd signal_fd_, timer_fd_;
  std::unique_ptr<CandumpRecorder> recorder_;
  PeerSession<1024> session_;
  std::uint64_t next_sequence_ = 0;
  BridgeCounters counters_;
  BridgeCounters at_last_stats_;
  std::uint64_t bus_bits_ = 0, bus_bits_at_last_stats_ = 0;
  LatencyHistogram latency_;
  ClockEstimate clock_;
  bool can_down_ = false;
  std::int64_t started_us_ = 0, last_stats_us_ = 0, last_probe_us_ = 0, last_can_check_us_ = 0;
  bool warned_reflection_ = false;
};

}  // namespace lever::bridge
