#include "relay.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sodium.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>

#include "lever/protocol/can_timing.hpp"

namespace lever::bridge {
namespace {

std::int64_t clock_us(clockid_t clock) {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}
std::int64_t steady_us() { return clock_us(CLOCK_MONOTONIC); }
std::int64_t wall_us() { return clock_us(CLOCK_REALTIME); }

// What to do when the CAN socket cannot be opened: the kernel may lack CAN altogether, or the interface is missing.
std::string can_open_hint(int error, const std::string& interface) {
  if (error == EAFNOSUPPORT || error == EPROTONOSUPPORT) {
    return "; this kernel has no CAN protocol family loaded: load it with `modprobe can-raw` (a virtual bus "
           "also needs `modprobe vcan`), or use a kernel built with CONFIG_CAN and CONFIG_CAN_RAW";
  }
  if (error == ENODEV) {
    return fmt::format(
        "; `ip link show {0}` lists it when it exists. A real controller: `ip link set {0} up type can bitrate "
        "1000000`; a virtual one: `modprobe vcan && ip link add dev {0} type vcan && ip link set {0} up`",
        interface);
  }
  return {};
}

// A bound on work per wake-up, so one busy direction cannot starve the other.
constexpr int kMaxDatagramsPerWakeup = 64;

}  // namespace

bool Relay::start(const BridgeConfig& config, const Key& key, std::string& error) {
  config_ = config;
  key_ = key;
  site_id_ = config.site_id ? *config.site_id : static_cast<std::uint8_t>(randombytes_uniform(256));
  if (config.peer_site_id && site_id_ == *config.peer_site_id) {
    // Only a random site id can meet the configured peer's (validate() refuses two equal configured ones).
    site_id_ = static_cast<std::uint8_t>(site_id_ + 1 + randombytes_uniform(255));
  }
  try {
    session_ = PeerSession<1024>(generate_epoch());
  } catch (const KeyError& e) {
    error = e.what();
    return false;
  }
  // Sequence numbers start at the wall clock in microseconds, so a restarted bridge is ahead of its old ones
  // and the peer's replay window accepts it (docs/datagram-format.md).
  next_sequence_ = static_cast<std::uint64_t>(wall_us());

  const auto local = platform::parse_socket_address(config.bind, error);
  if (!local) return false;
  const auto peer = platform::parse_socket_address(config.peer, error);
  if (!peer) return false;
  if (local->family() != peer->family()) {
    error = fmt::format("--bind {} and --peer {} are of different address families", config.bind, config.peer);
    return false;
  }
  peer_ = *peer;
  auto udp = platform::UdpSocket::open(*local);
  if (!udp) {
    error = udp.error().message;
    return false;
  }
  udp_.emplace(std::move(udp).value());
  platform::SocketCanConfig can_config;
  can_config.interface = config.can_interface;
  auto can = platform::SocketCan::open(can_config);
  if (!can) {
    error = can.error().message + can_open_hint(can.error().errno_value, config.can_interface);
    return false;
  }
  can_.emplace(std::move(can).value());

  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  signal_fd_.reset(::signalfd(-1, &signals, SFD_NONBLOCK | SFD_CLOEXEC));
  timer_fd_.reset(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  if (!signal_fd_ || !timer_fd_) {
    error = fmt::format("signalfd/timerfd: {}", std::strerror(errno));
    return false;
  }
  // A 50 ms housekeeping tick: stats, probes and following a CAN interface that went down; nothing on the relay
  // path.
  itimerspec tick{{0, 50'000'000}, {0, 50'000'000}};
  ::timerfd_settime(timer_fd_.get(), 0, &tick, nullptr);

  if (config.record) {
    RecorderConfig rc;
    rc.path = *config.record;
    rc.rotate_bytes = config.record_rotate_bytes;
    rc.keep_files = config.record_keep_files;
    try {
      recorder_ = std::make_unique<CandumpRecorder>(rc);
    } catch (const std::exception& e) {
      error = e.what();
      return false;
    }
  }
  started_us_ = last_stats_us_ = steady_us();
  last_probe_us_ = started_us_ - static_cast<std::int64_t>(config.probe_interval_s * 1e6);  // probe at once
  return true;
}

bool Relay::send(Datagram& d) {
  d.sender = site_id_;
  d.epoch = session_.own_epoch();
  d.peer_epoch = session_.peer_epoch();
  d.sequence = next_sequence_++;
  d.timestamp_us = static_cast<std::uint64_t>(steady_us());
  std::array<std::uint8_t, kMaxDatagramSize> buffer;
  const auto encoded = encode(d, key_, buffer);
  if (!encoded) return false;  // cannot happen for frames we built; counted by the caller as a send failure
  if (udp_->send_to(std::span(buffer.data(), encoded.size), peer_) != platform::UdpStatus::ok) {
    ++counters_.send_failures;
    return false;
  }
  return true;
}

void Relay::relay_can_to_network() {
  // Every frame read in this wake-up goes out now; frames that arrived together share one datagram.
  Datagram d;
  d.kind = Kind::data;
  std::int64_t timestamp = 0;
  // Recorded after the send, so that the recorder's copy is not on the way out.
  std::array<std::pair<std::int64_t, protocol::CanFrame>, kMaxFrames> read;
  std::size_t read_count = 0;
  while (d.frame_count < kMaxFrames && read_count < read.size() && !can_down_) {
    protocol::CanFrame frame;
    const auto status = can_->read(frame, timestamp);
    if (status == platform::IoStatus::skipped) continue;
    if (status == platform::IoStatus::interface_down || status == platform::IoStatus::interface_gone ||
        status == platform::IoStatus::error) {
      can_down_ = true;  // the socket stays: check_can() follows the interface until it is back
      break;
    }
    if (status != platform::IoStatus::ok) break;
    bus_bits_ += static_cast<std::uint64_t>(protocol::frame_bits_worst_case(frame.dlc));
    read[read_count++] = {timestamp != 0 ? timestamp : wall_us(), frame};
    if (!config_.allow_to_network.allows(frame.id)) {
      ++counters_.to_network.disallowed;
      continue;
    }
    d.frames[d.frame_count++] = frame;
  }
  if (d.frame_count > 0 && send(d)) {
    counters_.to_network.frames += d.frame_count;
    ++counters_.to_network.datagrams;
  }
  if (recorder_) {
    for (std::size_t i = 0; i < read_count; ++i)
      recorder_->record(read[i].first, config_.can_interface, read[i].second);
  }
}

void Relay::relay_network_to_can() {
  std::array<std::uint8_t, kMaxDatagramSize + 1> buffer;
  for (int i = 0; i < kMaxDatagramsPerWakeup; ++i) {
    std::size_t size = 0;
    platform::SocketAddress from;
    if (udp_->receive(buffer, size, from) != platform::UdpStatus::ok) return;
    const std::int64_t arrival = steady_us();
    if (!(from == peer_)) {
      ++counters_.foreign_source;  // not even worth a HMAC
      continue;
    }
    Datagram d;
    // A datagram longer than the buffer was truncated by the kernel: decode sees the real size and refuses.
    const auto error = size > buffer.size() ? WireError::oversized : decode(std::span(buffer.data(), size), key_, d);
    if (error == WireError::bad_tag) {
      ++counters_.auth_failures;
      continue;
    }
    if (error != WireError::none) {
      ++counters_.malformed;
      continue;
    }
    if (d.sender == site_id_) {
      ++counters_.reflected;
      if (!warned_reflection_) {
        fmt::print(stderr,
                   "lever-bridge: datagrams carry our own site id {}: reflected, or the peer uses the same "
                   "id (set --site-id differently at each end)\n",
                   site_id_);
        warned_reflection_ = true;
      }
      continue;
    }
    if (config_.peer_site_id && d.sender != *config_.peer_site_id) {
      ++counters_.wrong_site;
      continue;
    }
    const auto admitted = session_.admit(d.sequence, d.epoch, d.peer_epoch);
    if (admitted.admission == Admission::duplicate) {
      ++counters_.duplicates;
      continue;
    }
    if (admitted.admission == Admission::too_old) {
      ++counters_.too_old;
      continue;
    }
    if (admitted.replay.reordered()) ++counters_.reordered;
    counters_.sequence_gaps += admitted.replay.gap;
    if (admitted.peer_epoch_changed) {
      // First contact or a restarted peer: it takes our datagrams only once they echo its new epoch, so one goes
      // out now rather than at the next probe or CAN frame.
      ++counters_.peer_epochs;
      send_probe();
    }
    if (!admitted.fresh()) {
      ++counters_.stale;
      // A stale probe request is still answered: the reply echoes the requester's epoch, which is how a restarted
      // peer starts to take our traffic. Nothing else of a stale datagram is acted on.
      if (d.kind != Kind::probe_request) continue;
    }

    switch (d.kind) {
      case Kind::probe_request: {
        Datagram reply = make_probe_reply(d, site_id_, 0, static_cast<std::uint64_t>(arrival),
                                          static_cast<std::uint64_t>(steady_us()));
        send(reply);
        break;
      }
      case Kind::probe_reply: {
        const auto timing = probe_timing(d, static_cast<std::uint64_t>(arrival));
        clock_.round_trip_us = timing.round_trip_us;
        clock_.offset_us = timing.offset_us;
        ++counters_.probe_replies;
        break;
      }
      case Kind::data:
        handle_data(d, arrival);
        break;
    }
  }
}

void Relay::handle_data(const Datagram& d, std::int64_t arrival_us) {
  ++counters_.from_network.datagrams;
  // One-way latency: the peer's send time on our clock is its timestamp minus the clock offset.
  if (clock_.offset_us) latency_.add(arrival_us - (static_cast<std::int64_t>(d.timestamp_us) - *clock_.offset_us));
  const std::string& record_name =
      config_.record_network_interface.empty() ? config_.can_interface : config_.record_network_interface;
  for (const auto& frame : d.frame_list()) {
    if (!config_.allow_from_network.allows(frame.id)) {
      ++counters_.from_network.disallowed;
      continue;
    }
    if (can_down_) {
      ++counters_.can_down_drops;
      continue;
    }
    const auto status = can_->write(frame);
    if (status == platform::IoStatus::ok) {
      ++counters_.from_network.frames;
      bus_bits_ += static_cast<std::uint64_t>(protocol::frame_bits_worst_case(frame.dlc));
      if (recorder_) recorder_->record(wall_us(), record_name, frame);
    } else if (status == platform::IoStatus::would_block) {
      ++counters_.can_tx_full;
    } else {
      ++counters_.can_down_drops;
      can_down_ = true;
    }
  }
}

void Relay::check_can() {
  if (can_->recover() != platform::LinkState::up) return;
  can_down_ = false;
  ++counters_.can_reopens;
  fmt::print(stderr, "lever-bridge: {} is back\n", config_.can_interface);
}

void Relay::send_probe() {
  last_probe_us_ = steady_us();
  Datagram probe;
  probe.kind = Kind::probe_request;
  if (send(probe)) ++counters_.probes_sent;
}

void Relay::on_timer() {
  std::uint64_t expirations = 0;
  while (::read(timer_fd_.get(), &expirations, sizeof expirations) > 0) {
  }
  const std::int64_t now = steady_us();
  if (can_down_ && now - last_can_check_us_ >= 500'000) {
    last_can_check_us_ = now;
    check_can();
  }
  if (now - last_probe_us_ >= static_cast<std::int64_t>(config_.probe_interval_s * 1e6)) send_probe();
  const double interval = static_cast<double>(now - last_stats_us_) * 1e-6;
  if (config_.stats_json && interval >= config_.stats_interval_s) {
    print_stats(interval);
    last_stats_us_ = now;
  }
}

void Relay::print_stats(double interval_s) {
  const auto& c = counters_;
  const auto& p = at_last_stats_;
  auto rate = [interval_s](std::uint64_t now, std::uint64_t before) {
    return static_cast<double>(now - before) / interval_s;
  };
  auto opt = [](const auto& v) { return v ? nlohmann::json(*v) : nlohmann::json(); };
  nlohmann::json line{
      {"uptime_s", static_cast<double>(steady_us() - started_us_) * 1e-6},
      {"to_network",
       {{"frames", c.to_network.frames},
        {"frames_per_s", rate(c.to_network.frames, p.to_network.frames)},
        {"datagrams", c.to_network.datagrams},
        {"disallowed", c.to_network.disallowed},
        {"send_failures", c.send_failures},
        {"peer_unreachable", c.peer_unreachable}}},
      {"from_network",
       {{"frames", c.from_network.frames},
        {"frames_per_s", rate(c.from_network.frames, p.from_network.frames)},
        {"datagrams", c.from_network.datagrams},
        {"disallowed", c.from_network.disallowed},
        {"sequence_gaps", c.sequence_gaps},
        {"reordered", c.reordered},
        {"duplicates", c.duplicates},
        {"too_old", c.too_old},
        {"auth_failures", c.auth_failures},
        {"malformed", c.malformed},
        {"foreign_source", c.foreign_source},
        {"reflected", c.reflected},
        {"wrong_site", c.wrong_site},
        {"stale", c.stale},
        {"peer_epochs", c.peer_epochs},
        {"can_down_drops", c.can_down_drops},
        {"can_tx_full", c.can_tx_full}}},
      {"latency_us",
       {{"samples", latency_.count()},
        {"p50", opt(latency_.percentile(0.5))},
        {"p99", opt(latency_.percentile(0.99))},
        {"max", latency_.count() ? nlohmann::json(latency_.max()) : nlohmann::json()}}},
      {"round_trip_us", opt(clock_.round_trip_us)},
      {"clock_offset_us", opt(clock_.offset_us)},
      {"bus_load", static_cast<double>(bus_bits_ - bus_bits_at_last_stats_) / (config_.can_bitrate * interval_s)},
      {"can", can_down_ ? "down" : "up"},
      {"can_reopens", c.can_reopens},
      {"can_rx_kernel_drops", can_->kernel_drops()},
  };
  if (recorder_) {
    const auto r = recorder_->stats();
    line["recording"] = {{"recorded", r.recorded},
                         {"dropped_queue_full", r.dropped_queue_full},
                         {"rotations", r.rotations},
                         {"write_errors", r.write_errors}};
  }
  fmt::print("{}\n", line.dump());
  std::fflush(stdout);
  at_last_stats_ = counters_;
  bus_bits_at_last_stats_ = bus_bits_;
  latency_.clear();
}

int Relay::run() {
  while (true) {
    pollfd fds[4] = {{signal_fd_.get(), POLLIN, 0},
                     {timer_fd_.get(), POLLIN, 0},
                     {udp_->fd(), POLLIN, 0},
                     {can_down_ ? -1 : can_->fd(), POLLIN, 0}};
    if (::poll(fds, 4, -1) < 0) {
      if (errno == EINTR) continue;
      fmt::print(stderr, "lever-bridge: poll: {}\n", std::strerror(errno));
      return 1;
    }
    if (fds[0].revents & POLLIN) break;  // SIGINT, SIGTERM or SIGHUP
    if (fds[3].revents & (POLLIN | POLLERR)) relay_can_to_network();
    if (fds[2].revents & POLLIN) relay_network_to_can();
    if (fds[2].revents & POLLERR) counters_.peer_unreachable += static_cast<std::uint64_t>(udp_->drain_errors());
    if (fds[1].revents & POLLIN) on_timer();
  }
  if (config_.stats_json) print_stats(static_cast<double>(steady_us() - last_stats_us_) * 1e-6);
  recorder_.reset();  // drains, fsyncs and closes the log
  return 0;
}

}  // namespace lever::bridge
