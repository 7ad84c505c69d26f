#include "relay.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <poll.h>
#include <sodium.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
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

// The relay threads' wake-up call: it only has to exist, so that a blocked recvmmsg returns EINTR.
void on_wake_signal(int) {}

// Frames per wake-up of the CAN thread: two full datagrams, so that a burst costs one sendmmsg, not two sends.
constexpr std::size_t kCanBatch = 2 * kMaxFrames;
// Datagrams per wake-up of the network thread: a bound on the frames one sendmmsg writes (16 x 32).
constexpr std::size_t kUdpBatch = 16;

constexpr std::size_t kCanControlSize = CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t));

// The threads' stacks: the relay threads need some 60 KiB (their batches live there); glibc's default of 8 MiB
// each would all be locked and resident under mlockall.
constexpr std::size_t kThreadStackBytes = 512 * 1024;

bool set_blocking(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  return flags >= 0 && ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) == 0;
}

}  // namespace

Relay::~Relay() { stop_relay_threads(); }

bool Relay::start(const BridgeConfig& config, const Key& key, std::string& error) {
  config_ = config;
  // Every thread of the process from here on (the recorder's writer, the relay threads) gets this stack size.
  pthread_attr_t attributes;
  if (::pthread_attr_init(&attributes) == 0) {
    ::pthread_attr_setstacksize(&attributes, kThreadStackBytes);
    ::pthread_setattr_default_np(&attributes);
    ::pthread_attr_destroy(&attributes);
  }
  mac_key_.emplace(key);
  record_network_name_ =
      config.record_network_interface.empty() ? config.can_interface : config.record_network_interface;
  site_id_ = config.site_id ? *config.site_id : static_cast<std::uint8_t>(randombytes_uniform(256));
  if (config.peer_site_id && site_id_ == *config.peer_site_id) {
    // Only a random site id can meet the configured peer's (validate() refuses two equal configured ones).
    site_id_ = static_cast<std::uint8_t>(site_id_ + 1 + randombytes_uniform(255));
  }
  try {
    own_epoch_ = generate_epoch();
    session_ = PeerSession<1024>(own_epoch_);
  } catch (const KeyError& e) {
    error = e.what();
    return false;
  }
  // Sequence numbers start at the wall clock in microseconds, so a restarted bridge is ahead of its old ones
  // and the peer's replay window accepts it (docs/datagram-format.md).
  next_sequence_.store(static_cast<std::uint64_t>(wall_us()));

  const auto local = board::parse_socket_address(config.bind, error);
  if (!local) return false;
  const auto peer = board::parse_socket_address(config.peer, error);
  if (!peer) return false;
  if (local->family() != peer->family()) {
    error = fmt::format("--bind {} and --peer {} are of different address families", config.bind, config.peer);
    return false;
  }
  peer_ = *peer;
  auto udp = board::UdpSocket::open(*local);
  if (!udp) {
    error = udp.error().message;
    return false;
  }
  udp_.emplace(std::move(udp).value());
  udp_fd_ = udp_->fd();
  // The network thread sleeps in recvmmsg; every send says MSG_DONTWAIT for itself.
  if (!set_blocking(udp_fd_)) {
    error = fmt::format("UDP socket: fcntl: {}", std::strerror(errno));
    return false;
  }
  board::SocketCanConfig can_config;
  can_config.interface = config.can_interface;
  can_config.blocking = true;  // the CAN thread sleeps in recvmmsg; writes say MSG_DONTWAIT
  auto can = board::SocketCan::open(can_config);
  if (!can) {
    error = can.error().message + can_open_hint(can.error().errno_value, config.can_interface);
    return false;
  }
  can_.emplace(std::move(can).value());
  can_fd_ = can_->fd();
  // The kernel's default, made explicit: the frames we write must not come back to our own reader (they would
  // go back to the peer), while candump and the levers on the bus see them (CAN_RAW_LOOPBACK stays on).
  const int off = 0;
  if (::setsockopt(can_fd_, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, sizeof off) != 0) {
    error = fmt::format("{}: CAN_RAW_RECV_OWN_MSGS: {}", config.can_interface, std::strerror(errno));
    return false;
  }

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
  // Without SA_RESTART: the kick must end the relay threads' recvmmsg, not restart it.
  struct sigaction wake {};
  wake.sa_handler = on_wake_signal;
  sigemptyset(&wake.sa_mask);
  wake.sa_flags = 0;
  if (::sigaction(SIGUSR1, &wake, nullptr) != 0) {
    error = fmt::format("sigaction(SIGUSR1): {}", std::strerror(errno));
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
    rc.rings = 2;  // kRecorderRingCanToNetwork, kRecorderRingNetworkToCan
    // The writer's wake-ups are what the recorder costs the relay: on one CPU each is a context switch and a
    // write(2) the relay's frames can meet (docs/bridge.md has the measurements). 20 ms is 400 frames at 20 kHz in
    // a ring of 65536.
    rc.poll_interval = std::chrono::milliseconds(20);
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
  d.epoch = own_epoch_;
  d.peer_epoch = peer_epoch_.load(std::memory_order_relaxed);
  d.sequence = next_sequence_.fetch_add(1, std::memory_order_relaxed);
  d.timestamp_us = static_cast<std::uint64_t>(steady_us());
  std::array<std::uint8_t, kMaxDatagramSize> buffer;
  const auto encoded = encode(d, *mac_key_, buffer);
  if (!encoded) return false;  // cannot happen for datagrams we built
  if (::sendto(udp_fd_, buffer.data(), encoded.size, MSG_DONTWAIT, peer_.get(), peer_.length) < 0) {
    ++counters_.send_failures;
    return false;
  }
  return true;
}

void Relay::send_probe() {
  Datagram probe;
  probe.kind = Kind::probe_request;
  if (send(probe)) ++counters_.probes_sent;
}

// ---- CAN -> network ----

bool Relay::wait_while_can_down() {
  for (;;) {
    const std::uint32_t seen = wake_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_acquire)) return false;
    if (!can_down_.load(std::memory_order_acquire)) return true;
    wake_.wait(seen, std::memory_order_acquire);
  }
}

void Relay::can_to_network() {
  std::array<can_frame, kCanBatch> raw{};
  std::array<iovec, kCanBatch> iov{};
  std::array<mmsghdr, kCanBatch> in{};
  struct alignas(cmsghdr) Control {
    char bytes[kCanControlSize];
  };
  std::array<Control, kCanBatch> control{};
  for (std::size_t i = 0; i < kCanBatch; ++i) {
    iov[i] = {&raw[i], sizeof raw[i]};
    in[i].msg_hdr.msg_iov = &iov[i];
    in[i].msg_hdr.msg_iovlen = 1;
    in[i].msg_hdr.msg_control = control[i].bytes;
  }
  std::array<std::int64_t, kCanBatch> stamps{};
  std::array<protocol::CanFrame, kCanBatch> frames{};
  constexpr std::size_t kMaxDatagrams = kCanBatch / kMaxFrames;
  std::array<Datagram, kMaxDatagrams> datagrams{};
  std::array<std::array<std::uint8_t, kMaxDatagramSize>, kMaxDatagrams> wire{};
  std::array<iovec, kMaxDatagrams> out_iov{};
  std::array<mmsghdr, kMaxDatagrams> out{};

  while (!stop_.load(std::memory_order_relaxed)) {
    if (can_down_.load(std::memory_order_acquire) && !wait_while_can_down()) break;
    for (auto& m : in) m.msg_hdr.msg_controllen = kCanControlSize;  // the kernel shrinks it to what it wrote
    const int got = ::recvmmsg(can_fd_, in.data(), kCanBatch, MSG_WAITFORONE, nullptr);
    if (got < 0) {
      // EINTR: the housekeeping thread's kick (stop, or a reopened socket). Anything else (ENETDOWN: the
      // interface went down; ENODEV: it was removed) hands the socket to the housekeeping thread until it is back.
      if (errno != EINTR) can_down_.store(true, std::memory_order_release);
      continue;
    }

    std::size_t count = 0;
    std::uint32_t socket_drops = socket_drops_seen_;
    for (std::size_t i = 0; i < static_cast<std::size_t>(got); ++i) {
      std::int64_t stamp = 0;
      msghdr& h = in[i].msg_hdr;
      for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
        if (c->cmsg_level != SOL_SOCKET) continue;
        if (c->cmsg_type == SO_TIMESTAMP) {
          timeval tv;
          std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
          stamp = static_cast<std::int64_t>(tv.tv_sec) * 1'000'000 + tv.tv_usec;
        } else if (c->cmsg_type == SO_RXQ_OVFL) {
          std::memcpy(&socket_drops, CMSG_DATA(c), sizeof socket_drops);
        }
      }
      const can_frame& r = raw[i];
      // Classic 11-bit data frames only: extended, remote, error and CAN FD frames are not the lever protocol's.
      if (in[i].msg_len != sizeof r || r.can_dlc > 8 || (r.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)))
        continue;
      protocol::CanFrame& f = frames[count];
      f.id = r.can_id & CAN_SFF_MASK;
      f.dlc = r.can_dlc;
      std::memcpy(f.data.data(), r.data, 8);
      stamps[count++] = stamp;
    }
    // A reopened socket counts from 0 again.
    can_rx_kernel_drops_ += socket_drops >= socket_drops_seen_ ? socket_drops - socket_drops_seen_
                                                               : static_cast<std::uint64_t>(socket_drops);
    socket_drops_seen_ = socket_drops;

    std::size_t datagram_count = 0;
    for (std::size_t i = 0; i < count; ++i) {
      bus_bits_to_network_ += static_cast<std::uint64_t>(protocol::frame_bits_worst_case(frames[i].dlc));
      if (!config_.allow_to_network.allows(frames[i].id)) {
        ++counters_.to_network.disallowed;
        continue;
      }
      if (datagram_count == 0 || datagrams[datagram_count - 1].frame_count == kMaxFrames) {
        Datagram& d = datagrams[datagram_count++];
        d.kind = Kind::data;
        d.frame_count = 0;
      }
      Datagram& d = datagrams[datagram_count - 1];
      d.frames[d.frame_count++] = frames[i];
    }
    if (datagram_count > 0) {
      const auto now = static_cast<std::uint64_t>(steady_us());
      const std::uint64_t peer_epoch = peer_epoch_.load(std::memory_order_relaxed);
      const std::uint64_t first_sequence = next_sequence_.fetch_add(datagram_count, std::memory_order_relaxed);
      for (std::size_t k = 0; k < datagram_count; ++k) {
        Datagram& d = datagrams[k];
        d.sender = site_id_;
        d.epoch = own_epoch_;
        d.peer_epoch = peer_epoch;
        d.sequence = first_sequence + k;
        d.timestamp_us = now;
        const auto encoded = encode(d, *mac_key_, wire[k]);
        out_iov[k] = {wire[k].data(), encoded.size};
        out[k].msg_hdr = {};
        out[k].msg_hdr.msg_name = const_cast<sockaddr*>(peer_.get());
        out[k].msg_hdr.msg_namelen = peer_.length;
        out[k].msg_hdr.msg_iov = &out_iov[k];
        out[k].msg_hdr.msg_iovlen = 1;
      }
      std::size_t sent = 0;
      while (sent < datagram_count) {
        const int n =
            ::sendmmsg(udp_fd_, out.data() + sent, static_cast<unsigned>(datagram_count - sent), MSG_DONTWAIT);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
          ++counters_.send_failures;  // this one; the next is tried on its own
          ++sent;
          continue;
        }
        for (std::size_t k = sent; k < sent + static_cast<std::size_t>(n); ++k) {
          counters_.to_network.frames += datagrams[k].frame_count;
          ++counters_.to_network.datagrams;
        }
        sent += static_cast<std::size_t>(n);
      }
    }
    // After the send: the recorder's copy is not on the way out.
    if (recorder_) {
      for (std::size_t i = 0; i < count; ++i) {
        recorder_->record(kRecorderRingCanToNetwork, stamps[i] != 0 ? stamps[i] : wall_us(), config_.can_interface,
                          frames[i]);
      }
    }
  }
}

// ---- network -> CAN ----

void Relay::network_to_can() {
  std::array<std::array<std::uint8_t, kMaxDatagramSize + 1>, kUdpBatch> buffers{};
  std::array<iovec, kUdpBatch> iov{};
  std::array<sockaddr_storage, kUdpBatch> from{};
  std::array<mmsghdr, kUdpBatch> in{};
  for (std::size_t i = 0; i < kUdpBatch; ++i) {
    iov[i] = {buffers[i].data(), buffers[i].size()};
    in[i].msg_hdr.msg_iov = &iov[i];
    in[i].msg_hdr.msg_iovlen = 1;
    in[i].msg_hdr.msg_name = &from[i];
  }
  Datagram d;
  board::SocketAddress source;

  while (!stop_.load(std::memory_order_relaxed)) {
    for (auto& m : in) m.msg_hdr.msg_namelen = sizeof(sockaddr_storage);
    // MSG_TRUNC: msg_len is the datagram's real length, so an oversized one is recognised as such.
    const int got = ::recvmmsg(udp_fd_, in.data(), kUdpBatch, MSG_WAITFORONE | MSG_TRUNC, nullptr);
    if (got < 0) {
      // An ICMP error about an earlier send (IP_RECVERR) is reported here once; its details are in the error queue.
      if (errno != EINTR) counters_.peer_unreachable += static_cast<std::uint64_t>(udp_->drain_errors());
      continue;
    }
    const std::int64_t arrival = steady_us();
    for (std::size_t i = 0; i < static_cast<std::size_t>(got); ++i) {
      std::memcpy(&source.storage, &from[i], sizeof from[i]);
      source.length = in[i].msg_hdr.msg_namelen;
      if (!(source == peer_)) {
        ++counters_.foreign_source;  // not even worth a HMAC
        continue;
      }
      const std::size_t size = in[i].msg_len;
      const auto error =
          size > buffers[i].size() ? WireError::oversized : decode(std::span(buffers[i].data(), size), *mac_key_, d);
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
        // First contact or a restarted peer: it takes our datagrams only once they echo its new epoch, so one
        // goes out now rather than at the next probe or CAN frame.
        peer_epoch_.store(session_.peer_epoch(), std::memory_order_relaxed);
        ++counters_.peer_epochs;
        send_probe();
      }
      if (!admitted.fresh()) {
        ++counters_.stale;
        // A stale probe request is still answered: the reply echoes the requester's epoch, which is how a
        // restarted peer starts to take our traffic. Nothing else of a stale datagram is acted on.
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
          round_trip_us_.store(timing.round_trip_us, std::memory_order_relaxed);
          offset_us_.store(timing.offset_us, std::memory_order_relaxed);
          ++counters_.probe_replies;
          break;
        }
        case Kind::data:
          collect_frames(d, arrival);
          break;
      }
    }
    write_collected();
  }
}

void Relay::collect_frames(const Datagram& d, std::int64_t arrival_us) {
  ++counters_.from_network.datagrams;
  // One-way latency: the peer's send time on our clock is its timestamp minus the clock offset.
  if (const std::int64_t offset = offset_us_.load(std::memory_order_relaxed); offset != kNoEstimate)
    latency_.add(arrival_us - (static_cast<std::int64_t>(d.timestamp_us) - offset));
  for (const auto& frame : d.frame_list()) {
    if (!config_.allow_from_network.allows(frame.id)) {
      ++counters_.from_network.disallowed;
      continue;
    }
    if (can_down_.load(std::memory_order_relaxed)) {
      ++counters_.can_down_drops;
      continue;
    }
    collected_frames_[collected_++] = frame;  // kUdpBatch datagrams of at most kMaxFrames: always room
  }
}

void Relay::write_collected() {
  if (collected_ == 0) return;
  std::array<can_frame, 16 * kMaxFrames> raw;
  std::array<iovec, 16 * kMaxFrames> iov;
  std::array<mmsghdr, 16 * kMaxFrames> out;
  static_assert(raw.size() == kUdpBatch * kMaxFrames);
  for (std::size_t i = 0; i < collected_; ++i) {
    const auto& f = collected_frames_[i];
    raw[i] = {};
    raw[i].can_id = f.id & CAN_SFF_MASK;
    raw[i].can_dlc = f.dlc > 8 ? 8 : f.dlc;
    std::memcpy(raw[i].data, f.data.data(), 8);
    iov[i] = {&raw[i], sizeof raw[i]};
    out[i].msg_hdr = {};
    out[i].msg_hdr.msg_iov = &iov[i];
    out[i].msg_hdr.msg_iovlen = 1;
  }
  std::size_t done = 0;
  std::size_t written = 0;
  std::array<bool, 16 * kMaxFrames> ok{};
  while (done < collected_) {
    const int n = ::sendmmsg(can_fd_, out.data() + done, static_cast<unsigned>(collected_ - done), MSG_DONTWAIT);
    if (n > 0) {
      for (std::size_t i = done; i < done + static_cast<std::size_t>(n); ++i) ok[i] = true;
      done += static_cast<std::size_t>(n);
      written += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    const int error = n < 0 ? errno : EIO;
    if (error == EAGAIN || error == ENOBUFS) {
      // The interface's queue is full: this frame is lost, the next may fit.
      ++counters_.can_tx_full;
      ok[done++] = false;
      continue;
    }
    // ENETDOWN, ENXIO (removed) or worse: the rest waits for no one; housekeeping follows the interface.
    can_down_.store(true, std::memory_order_release);
    counters_.can_down_drops += collected_ - done;
    for (std::size_t i = done; i < collected_; ++i) ok[i] = false;
    done = collected_;
  }
  counters_.from_network.frames += written;
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < collected_; ++i) {
    if (ok[i]) bits += static_cast<std::uint64_t>(protocol::frame_bits_worst_case(collected_frames_[i].dlc));
  }
  bus_bits_from_network_ += bits;
  // After the write: the recorder's copy is not on the way out. One clock reading for the batch.
  if (recorder_) {
    const std::int64_t now = wall_us();
    for (std::size_t i = 0; i < collected_; ++i) {
      if (ok[i]) recorder_->record(kRecorderRingNetworkToCan, now, record_network_name_, collected_frames_[i]);
    }
  }
  collected_ = 0;
}

// ---- housekeeping ----

void Relay::check_can() {
  const std::uint64_t reopens = can_->reopens();
  if (can_->recover() != board::LinkState::up) return;
  can_down_.store(false, std::memory_order_release);
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_all();
  // After a reopen the CAN thread may still sit in recvmmsg on the old socket: send it to the new one.
  if (can_->reopens() != reopens && threads_[0].thread.joinable())
    ::pthread_kill(threads_[0].thread.native_handle(), SIGUSR1);
  ++counters_.can_reopens;
  fmt::print(stderr, "lever-bridge: {} is back\n", config_.can_interface);
}

void Relay::on_timer() {
  std::uint64_t expirations = 0;
  while (::read(timer_fd_.get(), &expirations, sizeof expirations) > 0) {
  }
  const std::int64_t now = steady_us();
  if (can_down_.load(std::memory_order_acquire) && now - last_can_check_us_ >= 500'000) {
    last_can_check_us_ = now;
    check_can();
  }
  if (now - last_probe_us_ >= static_cast<std::int64_t>(config_.probe_interval_s * 1e6)) {
    last_probe_us_ = now;
    send_probe();
  }
  const double interval = static_cast<double>(now - last_stats_us_) * 1e-6;
  if (config_.stats_json && interval >= config_.stats_interval_s) {
    print_stats(interval);
    last_stats_us_ = now;
  }
}

void Relay::print_stats(double interval_s) {
  const BridgeCounters c = counters_;  // one snapshot, so that the line is consistent with its rates
  const auto& p = at_last_stats_;
  const std::uint64_t bus_bits = bus_bits_to_network_.load() + bus_bits_from_network_.load();
  const LatencyHistogram latency = latency_.take_interval();
  auto rate = [interval_s](const Counter& now, const Counter& before) {
    return static_cast<double>(now.load() - before.load()) / interval_s;
  };
  auto opt = [](const auto& v) { return v ? nlohmann::json(*v) : nlohmann::json(); };
  auto estimate = [](const std::atomic<std::int64_t>& v) {
    const std::int64_t value = v.load(std::memory_order_relaxed);
    return value == kNoEstimate ? nlohmann::json() : nlohmann::json(value);
  };
  nlohmann::json line{
      {"uptime_s", static_cast<double>(steady_us() - started_us_) * 1e-6},
      {"to_network",
       {{"frames", c.to_network.frames.load()},
        {"frames_per_s", rate(c.to_network.frames, p.to_network.frames)},
        {"datagrams", c.to_network.datagrams.load()},
        {"disallowed", c.to_network.disallowed.load()},
        {"send_failures", c.send_failures.load()},
        {"peer_unreachable", c.peer_unreachable.load()}}},
      {"from_network",
       {{"frames", c.from_network.frames.load()},
        {"frames_per_s", rate(c.from_network.frames, p.from_network.frames)},
        {"datagrams", c.from_network.datagrams.load()},
        {"disallowed", c.from_network.disallowed.load()},
        {"sequence_gaps", c.sequence_gaps.load()},
        {"reordered", c.reordered.load()},
        {"duplicates", c.duplicates.load()},
        {"too_old", c.too_old.load()},
        {"auth_failures", c.auth_failures.load()},
        {"malformed", c.malformed.load()},
        {"foreign_source", c.foreign_source.load()},
        {"reflected", c.reflected.load()},
        {"wrong_site", c.wrong_site.load()},
        {"stale", c.stale.load()},
        {"peer_epochs", c.peer_epochs.load()},
        {"can_down_drops", c.can_down_drops.load()},
        {"can_tx_full", c.can_tx_full.load()}}},
      {"latency_us",
       {{"samples", latency.count()},
        {"p50", opt(latency.percentile(0.5))},
        {"p99", opt(latency.percentile(0.99))},
        {"max", latency.count() ? nlohmann::json(latency.max()) : nlohmann::json()}}},
      {"round_trip_us", estimate(round_trip_us_)},
      {"clock_offset_us", estimate(offset_us_)},
      {"bus_load", static_cast<double>(bus_bits - bus_bits_at_last_stats_) / (config_.can_bitrate * interval_s)},
      {"can", can_down_.load() ? "down" : "up"},
      {"can_reopens", c.can_reopens.load()},
      {"can_rx_kernel_drops", can_rx_kernel_drops_.load()},
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
  at_last_stats_ = c;
  bus_bits_at_last_stats_ = bus_bits;
}

void Relay::go_realtime() {
  if (config_.realtime_priority == 0) return;
  std::string refused;
  // Raising the soft limit works where the hard one allows it (LimitMEMLOCK=infinity, or root); a finite limit
  // is not tried against: MCL_FUTURE would make allocations fail later, past it, instead of mlockall now.
  const rlimit unlimited{RLIM_INFINITY, RLIM_INFINITY};
  ::setrlimit(RLIMIT_MEMLOCK, &unlimited);
  rlimit limit{};
  ::getrlimit(RLIMIT_MEMLOCK, &limit);
  if (limit.rlim_cur != RLIM_INFINITY) {
    refused = fmt::format("locked memory: RLIMIT_MEMLOCK is {} KiB, not unlimited", limit.rlim_cur / 1024);
  } else if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    refused = fmt::format("mlockall: {}", std::strerror(errno));
  }
  // Only the relay threads: housekeeping and the recorder's writer stay under the normal policy.
  const sched_param param{config_.realtime_priority};
  for (auto& t : threads_) {
    if (const int e = ::pthread_setschedparam(t.thread.native_handle(), SCHED_FIFO, &param); e != 0) {
      refused +=
          fmt::format("{}SCHED_FIFO {}: {}", refused.empty() ? "" : "; ", config_.realtime_priority, std::strerror(e));
      break;
    }
  }
  if (refused.empty()) return;
  fmt::print(stderr,
             "lever-bridge: WARNING: real-time scheduling refused ({}); relaying without it, so a busy host "
             "lengthens the latency tail. lever-bridge@.service grants it (LimitRTPRIO=40, LimitMEMLOCK=infinity); "
             "elsewhere CAP_SYS_NICE and CAP_IPC_LOCK do; --realtime-priority 0 asks for none\n",
             refused);
}

void Relay::stop_relay_threads() {
  stop_.store(true, std::memory_order_release);
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_all();
  for (auto& t : threads_) {
    if (!t.thread.joinable()) continue;
    // A kick that lands between the thread's look at stop_ and its recvmmsg is lost: kick until it is out.
    while (!t.done.load(std::memory_order_acquire)) {
      ::pthread_kill(t.thread.native_handle(), SIGUSR1);
      timespec pause{0, 2'000'000};
      ::nanosleep(&pause, nullptr);
    }
    t.thread.join();
  }
}

int Relay::run() {
  auto relay_thread = [this](RelayThread& t, void (Relay::*body)(), const char* name) {
    t.thread = std::thread([this, &t, body] {
      (this->*body)();
      t.done.store(true, std::memory_order_release);
    });
    ::pthread_setname_np(t.thread.native_handle(), name);
  };
  try {
    relay_thread(threads_[0], &Relay::can_to_network, "lever-can-rx");
    relay_thread(threads_[1], &Relay::network_to_can, "lever-net-rx");
    go_realtime();
  } catch (const std::system_error& e) {
    fmt::print(stderr, "lever-bridge: cannot start the relay threads: {}\n", e.what());
    stop_relay_threads();
    return 1;
  }

  while (true) {
    pollfd fds[2] = {{signal_fd_.get(), POLLIN, 0}, {timer_fd_.get(), POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      fmt::print(stderr, "lever-bridge: poll: {}\n", std::strerror(errno));
      stop_relay_threads();
      return 1;
    }
    if (fds[0].revents & POLLIN) break;  // SIGINT, SIGTERM or SIGHUP
    if (fds[1].revents & POLLIN) on_timer();
  }
  stop_relay_threads();
  if (config_.stats_json) print_stats(static_cast<double>(steady_us() - last_stats_us_) * 1e-6);
  recorder_.reset();  // drains, fsyncs and closes the log
  return 0;
}

}  // namespace lever::bridge
