#pragma once
// The bridge's relay at the kernel's pace: one thread per direction, each blocked in recvmmsg on its own socket,
// and a housekeeping thread (the caller of run()) for everything else.
//
//   CAN -> network  recvmmsg(MSG_WAITFORONE) on the CAN socket: every frame there when it wakes; the allowed ones
//                   in one datagram (two when more than 32 came), sent with one sendmmsg; then recorded.
//   network -> CAN  recvmmsg(MSG_WAITFORONE) on the UDP socket: every datagram there when it wakes; each checked
//                   (source, tag, site, replay window, epoch); the frames of all of them written with one sendmmsg
//                   on the CAN socket; then recorded; probes answered at once.
//   housekeeping    SIGINT, SIGTERM and SIGHUP (signalfd), a 50 ms timer: probes, statistics, following a CAN
//                   interface that went down or away (reopened under the same descriptor number).
//
// No poll on the path and no read that returns EAGAIN: a relay thread sleeps in the kernel until its socket has
// something. One CAN socket serves both directions, so the bridge never receives its own writes
// (CAN_RAW_RECV_OWN_MSGS is off, and set off explicitly), while other sockets on the bus do see them
// (CAN_RAW_LOOPBACK, the default). No lock on the path either: the sequence number is an atomic counter all
// senders draw from, the peer's epoch and the clock estimate are atomics the network thread publishes, the replay
// window is the network thread's alone, every counter has one writer (bridge_stats.hpp), and each relay thread
// records into a ring of its own.
//
// Stopping: the housekeeping thread sets the stop flag and sends SIGUSR1 to each relay thread (a handler that does
// nothing, installed without SA_RESTART, so that a blocked recvmmsg returns EINTR) until it has returned; the same
// kick sends the CAN thread back to its socket after a reopen.
#include <pthread.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "bridge_config.hpp"
#include "bridge_stats.hpp"
#include "candump_recorder.hpp"
#include "datagram.hpp"
#include "lever/board/socketcan.hpp"
#include "lever/board/udp_socket.hpp"
#include "lever/board/unique_fd.hpp"
#include "peer_session.hpp"

namespace lever::bridge {

class Relay {
 public:
  Relay() = default;
  Relay(const Relay&) = delete;
  Relay& operator=(const Relay&) = delete;
  ~Relay();

  // Everything that can fail at start-up fails here, with a message: returns false and sets `error`.
  bool start(const BridgeConfig& config, const Key& key, std::string& error);
  // Starts the relay threads and keeps house until SIGINT, SIGTERM or SIGHUP (blocked in every thread before
  // start()). Returns the exit code.
  int run();

 private:
  static constexpr std::size_t kRecorderRingCanToNetwork = 0;
  static constexpr std::size_t kRecorderRingNetworkToCan = 1;
  static constexpr std::int64_t kNoEstimate = INT64_MIN;

  // The relay threads.
  void can_to_network();
  void network_to_can();
  bool wait_while_can_down();  // false: stop
  // The network thread's handling of one authentic datagram's frames: appended to the batch for the CAN socket.
  void collect_frames(const Datagram& d, std::int64_t arrival_us);
  void write_collected();

  // Any thread: stamps and sends one datagram from the caller's buffer.
  bool send(Datagram& d);
  void send_probe();

  // Housekeeping.
  void on_timer();
  void check_can();
  void print_stats(double interval_s);
  void stop_relay_threads();
  // SCHED_FIFO for the relay threads and mlockall, as configured; where refused, one warning.
  void go_realtime();

  BridgeConfig config_;
  std::optional<MacKey> mac_key_;
  std::uint8_t site_id_ = 0;
  std::string record_network_name_;
  std::optional<board::SocketCan> can_;  // opened by start(); the housekeeping thread's (recover)
  std::optional<board::UdpSocket> udp_;  // opened by start()
  int can_fd_ = -1, udp_fd_ = -1;        // what the relay threads use; the same numbers across a CAN reopen
  board::SocketAddress peer_;
  board::UniqueFd signal_fd_, timer_fd_;
  std::unique_ptr<CandumpRecorder> recorder_;

  // Shared by all threads.
  std::atomic<std::uint64_t> next_sequence_{0};
  std::uint64_t own_epoch_ = 0;
  std::atomic<std::uint64_t> peer_epoch_{0};                                       // written by the network thread
  std::atomic<std::int64_t> round_trip_us_{kNoEstimate}, offset_us_{kNoEstimate};  // network thread
  std::atomic<bool> can_down_{false};  // set by either relay thread, cleared by housekeeping
  std::atomic<bool> stop_{false};
  std::atomic<std::uint32_t> wake_{0};  // bumped (and notified) when can_down_ is cleared or stop_ set
  BridgeCounters counters_;
  SharedLatencyHistogram latency_;  // network thread adds, housekeeping takes

  // The CAN -> network thread's.
  alignas(kCacheLine) Counter bus_bits_to_network_;
  Counter can_rx_kernel_drops_;  // summed over reopens
  std::uint32_t socket_drops_seen_ = 0;
  // The network -> CAN thread's.
  alignas(kCacheLine) Counter bus_bits_from_network_;
  PeerSession<1024> session_;
  bool warned_reflection_ = false;
  std::size_t collected_ = 0;
  std::array<protocol::CanFrame, 16 * kMaxFrames> collected_frames_{};

  // Housekeeping's.
  alignas(kCacheLine) BridgeCounters at_last_stats_;
  std::uint64_t bus_bits_at_last_stats_ = 0;
  std::int64_t started_us_ = 0, last_stats_us_ = 0, last_probe_us_ = 0, last_can_check_us_ = 0;

  struct RelayThread {
    std::thread thread;
    std::atomic<bool> done{false};
  };
  std::array<RelayThread, 2> threads_;
};

}  // namespace lever::bridge
