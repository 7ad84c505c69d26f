// lever-bench-bridge: what the lever-bridge datagram path costs on loopback. Prints one JSON object.
//
// 1. Latency: a ping-pong between two threads, each with its own UDP socket on 127.0.0.1, pinned to different
//    cores when there are two. One-way latency is RTT / 2 from steady_clock (CLOCK_MONOTONIC). Two variants,
//    interleaved in blocks (A B B A ...) so that drift and background load hit both alike:
//      raw:  sendto/recvfrom of a payload as large as an encoded 1-frame datagram (the baseline);
//      path: build a Datagram, encode (HMAC), sendto; recvfrom, decode (verify), check peer and sender,
//            ReplayWindow::accept, and the echo side answers with a new encoded datagram the same way.
//    Both sides wait in poll() before recvfrom, as the bridge's poll loop did until its relay threads (which
//    block in recvmmsg instead: docs/bridge.md, "Threads"), so the wake-up cost is in both.
// 2. Sustained rate: a paced sender thread (1 frame per datagram) against one receiver thread doing the
//    bridge's receive work; losses counted from the sequence numbers. Plus one unpaced run.
// 3. The codec's own cost: encode and decode in a tight loop, no I/O.
// On a shared machine the latency tail is mostly other work being scheduled first; --fifo N runs the two latency
// threads SCHED_FIFO to show the path without it (the JSON counts the stalls either way).
#include <fmt/format.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/utsname.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "datagram.hpp"
#include "key.hpp"
#include "lever/board/udp_socket.hpp"
#include "replay_window.hpp"

namespace {

namespace lb = lever::bridge;
namespace lio = lever::board;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;  // keys in the order written: context first, as a reader wants

constexpr std::uint8_t kSiteA = 1;  // the pinging / sending side
constexpr std::uint8_t kSiteB = 2;  // the echoing side
constexpr int kRcvBufRequest = 4 << 20;
constexpr std::size_t kReceiveBufferSize = 2048;  // larger than kMaxDatagramSize, as the format asks
// A raw payload starts with 0, never with the datagram magic 'L': the echo side tells the variants apart by
// one byte compare, so both variants share the sockets, the threads and the echo loop.
constexpr std::uint8_t kRawMarker = 0x00;
constexpr std::size_t kBlock = 250;    // round trips per block of one variant
constexpr int kReplyTimeoutMs = 1000;  // a lost round trip; loopback should never lose one
constexpr std::uint64_t kMaxLostRoundTrips = 10;
constexpr double kStallUs = 500.0;
constexpr auto kDrainIdle = std::chrono::milliseconds(200);  // receiver gives up this long after the last datagram

// Socket setup failures end the program with exit status 1 (see main).
class SetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ---- small helpers ----

double to_us(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

std::uint64_t micros(Clock::time_point t) {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count());
}

// Nearest-rank percentile of sorted samples.
double percentile(const std::vector<double>& sorted, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5);
  return sorted[std::min(k, sorted.size() - 1)];
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return percentile(v, 0.5);
}

// Percentiles, and how many samples were stalls: far beyond any path cost, they are the scheduler running other
// work first. When they reach 1 %, p99 measures the neighbours, not the path.
Json summary(std::vector<double> one_way_us) {
  std::sort(one_way_us.begin(), one_way_us.end());
  const auto stalls = one_way_us.end() - std::upper_bound(one_way_us.begin(), one_way_us.end(), kStallUs);
  return {{"p50", percentile(one_way_us, 0.50)},
          {"p90", percentile(one_way_us, 0.90)},
          {"p99", percentile(one_way_us, 0.99)},
          {"max", one_way_us.back()},
          {"stalls_over_500us", stalls}};
}

std::string first_line_of(const char* path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  }
  return "unknown";
}

std::string kernel_release() {
  utsname u{};
  return ::uname(&u) == 0 ? std::string(u.release) : "unknown";
}

// ---- CPUs ----

std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (::sched_getaffinity(0, sizeof set, &set) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

// Pins the calling thread; cpu < 0 leaves it to the scheduler.
bool pin_current_thread(int cpu) {
  if (cpu < 0) return false;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set) == 0;
}

// SCHED_FIFO for the calling thread (opt-in, latency threads only: they block in poll(), so they cannot starve
// the machine); takes the neighbours' scheduling out of the tail. priority 0 leaves the thread as it is.
bool make_fifo(int priority) {
  if (priority <= 0) return false;
  const sched_param param{priority};
  return ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param) == 0;
}

// The two threads of each test go to two different allowed CPUs; with one CPU they are not pinned.
struct Placement {
  int first = -1, second = -1;
};

Placement choose_cpus(const std::vector<int>& cpus) {
  if (cpus.size() < 2) return {};
  return {cpus[0], cpus[1]};
}

// ---- sockets ----

// One end of the loopback link: the socket and its own address, read back after binding to port 0.
struct Link {
  std::optional<lio::UdpSocket> socket;
  lio::SocketAddress address;
  int rcvbuf_granted = 0;  // getsockopt(SO_RCVBUF): the kernel reports twice the usable size
};

lio::SocketAddress local_address_of(int fd) {
  lio::SocketAddress address;
  address.length = sizeof address.storage;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&address.storage), &address.length) != 0)
    throw SetupError(fmt::format("getsockname: {}", std::strerror(errno)));
  return address;
}

// Binds 127.0.0.1 with a port the kernel picks, asks for a 4 MB receive buffer (capped by net.core.rmem_max,
// as it would be for the bridge, which has no CAP_NET_ADMIN) and reads back the port and what was granted.
void open_link(Link& link) {
  std::string error;
  const auto any_port = lio::parse_socket_address("127.0.0.1:0", error);
  if (!any_port) throw SetupError(error);
  auto opened = lio::UdpSocket::open(*any_port);
  if (!opened) throw SetupError(opened.error().message);
  link.socket.emplace(std::move(opened).value());
  const int fd = link.socket->fd();
  if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &kRcvBufRequest, sizeof kRcvBufRequest) != 0)
    throw SetupError(fmt::format("setsockopt(SO_RCVBUF): {}", std::strerror(errno)));
  socklen_t size = sizeof link.rcvbuf_granted;
  if (::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &link.rcvbuf_granted, &size) != 0)
    throw SetupError(fmt::format("getsockopt(SO_RCVBUF): {}", std::strerror(errno)));
  link.address = local_address_of(fd);
}

// Waits up to timeout_ms for `fd` to be readable (or writable); false on timeout.
bool wait_for(int fd, short events, int timeout_ms) {
  pollfd p{fd, events, 0};
  return ::poll(&p, 1, timeout_ms) > 0;
}

// Sends one datagram; on a full socket buffer waits for room rather than dropping, so every counted send is a
// datagram on the wire. Counts the waits into `waits` if given. Returns false on a real error.
bool send_all(lio::UdpSocket& socket, std::span<const std::uint8_t> bytes, const lio::SocketAddress& to,
              std::uint64_t* waits = nullptr) {
  for (;;) {
    const auto status = socket.send_to(bytes, to);
    if (status == lio::UdpStatus::ok) return true;
    if (status != lio::UdpStatus::would_block) return false;
    if (waits) ++*waits;
    wait_for(socket.fd(), POLLOUT, 100);
  }
}

// ---- the datagram ----

// One 8-byte CAN frame, as lever-bridge relays each frame of the 1 kHz link. `token` fills the data bytes so the
// pinging side can match an echo to its request.
lb::Datagram one_frame(std::uint8_t sender, std::uint64_t sequence, std::uint64_t token, Clock::time_point now) {
  lb::Datagram d;
  d.sender = sender;
  d.sequence = sequence;
  d.timestamp_us = micros(now);
  d.frame_count = 1;
  d.frames[0].id = 0x101;
  d.frames[0].dlc = 8;
  for (std::size_t i = 0; i < 8; ++i) d.frames[0].data[i] = static_cast<std::uint8_t>(token >> (8 * i));
  return d;
}

std::uint64_t token_of(const lever::protocol::CanFrame& frame) {
  std::uint64_t token = 0;
  for (std::size_t i = 0; i < 8; ++i) token |= std::uint64_t{frame.data[i]} << (8 * i);
  return token;
}

const std::size_t kOneFrameSize = lb::encoded_size(one_frame(kSiteA, 0, 0, {}));

// The receive-side checks of the bridge (host/bridge/relay.cpp), in its order: the source address (cheap, before
// any HMAC), decode (tag first), the site id, then the replay window. Returns the verdict, or nullopt when the
// datagram is not an authentic one from the peer.
template <std::size_t W>
std::optional<lb::ReplayResult> accept_datagram(std::span<const std::uint8_t> bytes, const lio::SocketAddress& from,
                                                const lio::SocketAddress& peer, std::uint8_t peer_site,
                                                const lb::MacKey& key, lb::ReplayWindow<W>& window, lb::Datagram& out) {
  if (!(from == peer)) return std::nullopt;
  if (lb::decode(bytes, key, out) != lb::WireError::none || out.sender != peer_site) return std::nullopt;
  return window.accept(out.sequence);
}

// ---- 1. latency ----

enum class Variant : std::uint8_t { raw, path };

// The echo side: answers raw payloads with the same bytes, and datagrams with a new datagram of its own.
void echo_loop(Link& self, const lio::SocketAddress& peer, const lb::MacKey& key, const std::atomic<bool>& stop) {
  std::array<std::uint8_t, kReceiveBufferSize> in{};
  std::array<std::uint8_t, lb::kMaxDatagramSize> out{};
  lb::ReplayWindow<> window;
  lb::Datagram received;
  lio::SocketAddress from;
  std::uint64_t sequence = 0;
  while (!stop.load(std::memory_order_relaxed)) {
    if (!wait_for(self.socket->fd(), POLLIN, 50)) continue;  // short timeout: notice `stop`
    std::size_t size = 0;
    if (self.socket->receive(in, size, from) != lio::UdpStatus::ok || size == 0 || size > in.size()) continue;
    const std::span<const std::uint8_t> bytes(in.data(), size);
    if (in[0] == kRawMarker) {
      send_all(*self.socket, bytes, peer);
      continue;
    }
    const auto verdict = accept_datagram(bytes, from, peer, kSiteA, key, window, received);
    if (!verdict || !verdict->accepted()) continue;
    const auto reply = one_frame(kSiteB, ++sequence, token_of(received.frames[0]), Clock::now());
    const auto encoded = lb::encode(reply, key, out);
    if (encoded) send_all(*self.socket, std::span<const std::uint8_t>(out.data(), encoded.size), peer);
  }
}

// The pinging side: one round trip at a time, timed from before the send to after the reply is accepted.
class Pinger {
 public:
  Pinger(Link& self, const lio::SocketAddress& peer, const lb::MacKey& key) : self_(self), peer_(peer), key_(key) {}

  // Round-trip time in microseconds, or nullopt if no matching reply came within kReplyTimeoutMs.
  std::optional<double> round_trip_us(Variant variant) {
    return variant == Variant::raw ? raw_round_trip() : path_round_trip();
  }

 private:
  std::optional<double> raw_round_trip() {
    const std::uint64_t token = ++token_;
    std::array<std::uint8_t, lb::kMaxDatagramSize> payload{};
    payload[0] = kRawMarker;
    std::memcpy(payload.data() + 1, &token, sizeof token);
    const std::span<const std::uint8_t> bytes(payload.data(), kOneFrameSize);
    const auto t0 = Clock::now();
    if (!send_all(*self_.socket, bytes, peer_)) return std::nullopt;
    for (;;) {
      std::size_t size = 0;
      if (!receive(size)) return std::nullopt;
      std::uint64_t echoed = 0;
      std::memcpy(&echoed, in_.data() + 1, sizeof echoed);
      if (size == kOneFrameSize && in_[0] == kRawMarker && echoed == token) break;  // else a stale echo
    }
    return to_us(Clock::now() - t0);
  }

  std::optional<double> path_round_trip() {
    const std::uint64_t token = ++token_;
    const auto t0 = Clock::now();
    const auto request = one_frame(kSiteA, ++sequence_, token, t0);
    const auto encoded = lb::encode(request, key_, out_);
    if (!encoded) return std::nullopt;
    if (!send_all(*self_.socket, std::span<const std::uint8_t>(out_.data(), encoded.size), peer_)) return std::nullopt;
    for (;;) {
      std::size_t size = 0;
      if (!receive(size)) return std::nullopt;
      const auto verdict =
          accept_datagram(std::span<const std::uint8_t>(in_.data(), size), from_, peer_, kSiteB, key_, window_, reply_);
      if (verdict && verdict->accepted() && reply_.frame_count == 1 && token_of(reply_.frames[0]) == token) break;
    }
    return to_us(Clock::now() - t0);
  }

  // poll() then recvfrom(), the bridge's way of waiting before its relay threads.
  bool receive(std::size_t& size) {
    for (;;) {
      if (!wait_for(self_.socket->fd(), POLLIN, kReplyTimeoutMs)) return false;
      const auto status = self_.socket->receive(in_, size, from_);
      if (status == lio::UdpStatus::ok) return size <= in_.size();
      if (status != lio::UdpStatus::would_block) return false;
    }
  }

  Link& self_;
  const lio::SocketAddress& peer_;
  const lb::MacKey& key_;
  std::array<std::uint8_t, kReceiveBufferSize> in_{};
  std::array<std::uint8_t, lb::kMaxDatagramSize> out_{};
  lb::ReplayWindow<> window_;
  lb::Datagram reply_;
  lio::SocketAddress from_;
  std::uint64_t token_ = 0, sequence_ = 0;
};

struct LatencySamples {
  std::vector<double> raw_one_way_us, path_one_way_us;
  std::uint64_t lost_round_trips = 0;
  bool pinned = false;
  bool fifo = false;  // both threads got SCHED_FIFO
};

// A B B A order: over every four blocks each variant runs once first and once second after the other.
Variant variant_of_block(std::size_t block) {
  const std::size_t phase = block % 4;
  return phase == 0 || phase == 3 ? Variant::raw : Variant::path;
}

LatencySamples run_ping_pong(Pinger& pinger, std::size_t round_trips, std::size_t warmup) {
  LatencySamples samples;
  samples.raw_one_way_us.reserve(round_trips);
  samples.path_one_way_us.reserve(round_trips);
  const std::size_t total = warmup + round_trips;
  std::array<std::size_t, 2> done{0, 0};
  for (std::size_t block = 0; done[0] < total || done[1] < total; ++block) {
    const Variant variant = variant_of_block(block);
    auto& count = done[static_cast<std::size_t>(variant)];
    auto& sink = variant == Variant::raw ? samples.raw_one_way_us : samples.path_one_way_us;
    for (std::size_t end = std::min(total, count + kBlock); count < end;) {
      const auto rtt = pinger.round_trip_us(variant);
      if (!rtt) {
        if (++samples.lost_round_trips > kMaxLostRoundTrips) return samples;
        continue;  // retry: a lost round trip says nothing about latency
      }
      if (count >= warmup) sink.push_back(*rtt / 2.0);
      ++count;
    }
  }
  return samples;
}

LatencySamples measure_latency(Link& a, Link& b, const lb::MacKey& key, Placement cpus, std::size_t round_trips,
                               int fifo_priority) {
  std::atomic<bool> stop{false};
  bool echo_pinned = false, echo_fifo = false;
  std::thread echo([&] {
    echo_pinned = pin_current_thread(cpus.second);
    echo_fifo = make_fifo(fifo_priority);
    echo_loop(b, a.address, key, stop);
  });
  LatencySamples samples;
  std::thread ping([&] {
    const bool pinned = pin_current_thread(cpus.first);
    const bool fifo = make_fifo(fifo_priority);
    Pinger pinger(a, b.address, key);
    samples = run_ping_pong(pinger, round_trips, std::max<std::size_t>(1000, round_trips / 20));
    samples.pinned = pinned;
    samples.fifo = fifo;
  });
  ping.join();
  stop = true;
  echo.join();
  samples.pinned = samples.pinned && echo_pinned;
  samples.fifo = samples.fifo && echo_fifo;
  return samples;
}

// ---- 2. sustained rate ----

struct SendTally {
  std::uint64_t sent = 0, send_waits = 0, send_errors = 0;
  Clock::time_point first{}, last{};
  double max_late_us = 0;  // worst lateness of a send against its schedule (a stall, then a burst)
};

struct ReceiveTally {
  std::uint64_t accepted = 0, duplicates = 0, too_old = 0, reordered = 0, gaps = 0, rejected = 0;
  Clock::time_point first{}, last{};
};

constexpr std::uint64_t kStillSending = std::numeric_limits<std::uint64_t>::max();

// Waits until `due`: sleeps (absolute, so errors do not accumulate) while far away, spins for the last stretch,
// since a sleep wakes tens of microseconds late and the period at 80 kHz is 12.5 us.
// steady_clock is CLOCK_MONOTONIC in libstdc++ on Linux, so its time points are valid clock_nanosleep deadlines.
void pace_until(Clock::time_point due) {
  constexpr auto kSpin = std::chrono::microseconds(60);
  if (due - Clock::now() > 2 * kSpin) {
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>((due - kSpin).time_since_epoch()).count();
    const timespec wake{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr);
  }
  while (Clock::now() < due) {
  }
}

// Sends 1-frame datagrams for `seconds`: at `rate` per second on an absolute schedule (a stall is caught up as
// a burst, so the average is the target), or as fast as possible when rate is 0.
SendTally send_frames(Link& self, const lio::SocketAddress& peer, const lb::MacKey& key, double rate, double seconds) {
  ::prctl(PR_SET_TIMERSLACK, 1UL);  // the default 50 us slack would make every sleep late
  SendTally tally;
  std::array<std::uint8_t, lb::kMaxDatagramSize> out{};
  const auto start = Clock::now() + std::chrono::milliseconds(20);  // let the receiver reach its poll()
  const auto end = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  const std::uint64_t count =
      rate > 0 ? static_cast<std::uint64_t>(rate * seconds) : std::numeric_limits<std::uint64_t>::max();
  pace_until(start);
  for (std::uint64_t i = 0; i < count; ++i) {
    Clock::time_point now;
    if (rate > 0) {
      const auto due = start + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(static_cast<double>(i) / rate));
      pace_until(due);
      now = Clock::now();
      tally.max_late_us = std::max(tally.max_late_us, to_us(now - due));
    } else {
      now = Clock::now();
      if (now >= end) break;
    }
    const auto encoded = lb::encode(one_frame(kSiteA, i + 1, i, now), key, out);
    if (!encoded ||
        !send_all(*self.socket, std::span<const std::uint8_t>(out.data(), encoded.size), peer, &tally.send_waits)) {
      ++tally.send_errors;
      continue;
    }
    if (tally.sent++ == 0) tally.first = now;
    tally.last = now;
  }
  return tally;
}

void count_verdict(const std::optional<lb::ReplayResult>& verdict, ReceiveTally& tally) {
  if (!verdict) {
    ++tally.rejected;
    return;
  }
  switch (verdict->verdict) {
    case lb::ReplayVerdict::accepted:
      ++tally.accepted;
      tally.gaps += verdict->gap;
      if (verdict->reordered()) ++tally.reordered;
      break;
    case lb::ReplayVerdict::duplicate:
      ++tally.duplicates;
      break;
    case lb::ReplayVerdict::too_old:
      ++tally.too_old;
      break;
  }
}

// The bridge's receive side as it was before its relay threads: poll(), then drain the socket, each datagram
// decoded, verified and passed through the replay window. Stops once every sent datagram is in, or kDrainIdle after
// the last one arrived once the sender is done (the rest were lost).
ReceiveTally receive_frames(Link& self, const lio::SocketAddress& peer, const lb::MacKey& key,
                            const std::atomic<std::uint64_t>& sent_total) {
  ReceiveTally tally;
  std::array<std::uint8_t, kReceiveBufferSize> in{};
  lb::ReplayWindow<> window;
  lb::Datagram datagram;
  lio::SocketAddress from;
  auto last_activity = Clock::now();
  for (;;) {
    const std::uint64_t total = sent_total.load(std::memory_order_acquire);
    if (total != kStillSending) {
      if (tally.accepted + tally.duplicates + tally.too_old + tally.rejected >= total) break;
      if (Clock::now() - last_activity > kDrainIdle) break;
    }
    if (!wait_for(self.socket->fd(), POLLIN, 10)) continue;
    std::size_t size = 0;
    while (self.socket->receive(in, size, from) == lio::UdpStatus::ok) {
      const auto now = Clock::now();
      if (tally.first == Clock::time_point{}) tally.first = now;
      tally.last = last_activity = now;
      if (size > in.size()) {
        ++tally.rejected;
        continue;
      }
      count_verdict(
          accept_datagram(std::span<const std::uint8_t>(in.data(), size), from, peer, kSiteA, key, window, datagram),
          tally);
    }
  }
  return tally;
}

double per_second(std::uint64_t n, Clock::time_point first, Clock::time_point last) {
  const double s = std::chrono::duration<double>(last - first).count();
  return s > 0 ? static_cast<double>(n) / s : 0.0;
}

struct RateRun {
  double target = 0;  // frames/s; 0 for the unpaced run
  SendTally send;
  ReceiveTally receive;
  std::uint64_t lost() const { return send.sent > receive.accepted ? send.sent - receive.accepted : 0; }
  double send_rate() const { return per_second(send.sent, send.first, send.last); }
  double receive_rate() const { return per_second(receive.accepted, receive.first, receive.last); }
  // The schedule was met on average: otherwise a loss-free run says nothing about the target rate.
  bool sender_kept_up() const { return target <= 0 || send_rate() >= 0.99 * target; }
  bool clean() const { return lost() == 0 && receive.duplicates == 0 && send.send_errors == 0; }
};

// Fresh sockets per run: nothing left over from the previous run can reach this run's replay window.
RateRun run_rate(const lb::MacKey& key, Placement cpus, double rate, double seconds) {
  Link sender, receiver;
  open_link(sender);
  open_link(receiver);
  RateRun run;
  run.target = rate;
  std::atomic<std::uint64_t> sent_total{kStillSending};
  std::thread rx([&] {
    pin_current_thread(cpus.second);
    run.receive = receive_frames(receiver, sender.address, key, sent_total);
  });
  std::thread tx([&] {
    pin_current_thread(cpus.first);
    run.send = send_frames(sender, receiver.address, key, rate, seconds);
    sent_total.store(run.send.sent, std::memory_order_release);
  });
  tx.join();
  rx.join();
  return run;
}

Json to_json(const RateRun& run) {
  Json j{{"achieved_send_frames_per_s", run.send_rate()},
         {"receive_frames_per_s", run.receive_rate()},
         {"sent", run.send.sent},
         {"received", run.receive.accepted},
         {"lost", run.lost()},
         {"window_gaps", run.receive.gaps},
         {"duplicates", run.receive.duplicates},
         {"reordered", run.receive.reordered},
         {"too_old", run.receive.too_old},
         {"rejected", run.receive.rejected},
         {"send_buffer_waits", run.send.send_waits},
         {"send_errors", run.send.send_errors}};
  if (run.target > 0) {
    j["target_frames_per_s"] = run.target;
    j["sender_kept_up"] = run.sender_kept_up();
    j["sender_max_late_us"] = run.send.max_late_us;
  }
  return j;
}

// ---- 3. codec cost ----

struct CodecCost {
  double encode_ns = 0, decode_ns = 0;
  std::size_t calls = 0;
};

// Batches of calls timed together (one clock read per batch, not per call); the median batch, per call.
// Encode and decode batches alternate, after a warm-up, so that frequency changes and neighbours hit both alike.
// With a lb::Key, the one-shot HMAC that hashes the key's padded blocks every call, for comparison.
template <typename AnyKey>
CodecCost measure_codec(const AnyKey& key) {
  constexpr int kWarmup = 20;
  constexpr int kBatches = 301;
  constexpr int kPerBatch = 100;
  std::array<std::uint8_t, lb::kMaxDatagramSize> buffer{}, scratch{};
  auto datagram = one_frame(kSiteA, 1, 0x1122334455667788, Clock::now());
  if (lb::encode(datagram, key, buffer).size != kOneFrameSize) throw std::runtime_error("encode failed");
  const std::span<const std::uint8_t> encoded(buffer.data(), kOneFrameSize);
  lb::Datagram decoded;
  std::size_t failures = 0;
  std::vector<double> encode_ns, decode_ns;
  for (int b = 0; b < kWarmup + kBatches; ++b) {
    const auto t0 = Clock::now();
    for (int i = 0; i < kPerBatch; ++i) {
      ++datagram.sequence;  // a new datagram each time, as in use
      failures += lb::encode(datagram, key, scratch).size != kOneFrameSize;
    }
    const auto t1 = Clock::now();
    for (int i = 0; i < kPerBatch; ++i) failures += lb::decode(encoded, key, decoded) != lb::WireError::none;
    const auto t2 = Clock::now();
    if (b < kWarmup) continue;
    encode_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / kPerBatch);
    decode_ns.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count() / kPerBatch);
  }
  if (failures != 0) throw std::runtime_error("the codec failed in the cost loop");
  return {median(encode_ns), median(decode_ns), static_cast<std::size_t>(kBatches) * kPerBatch};
}

// ---- output ----

Json machine_json(const std::vector<int>& cpus, Placement placement, bool pinned, int rcvbuf_granted) {
  return {{"cpus_online", std::thread::hardware_concurrency()},
          {"cpus_allowed", cpus},
          {"cpu_model", cpu_model()},
          {"kernel", kernel_release()},
          {"loadavg_at_start", first_line_of("/proc/loadavg")},
          {"net_core_rmem_max", first_line_of("/proc/sys/net/core/rmem_max")},
          {"so_rcvbuf_requested_bytes", kRcvBufRequest},
          {"so_rcvbuf_granted_bytes", rcvbuf_granted},
          {"so_rcvbuf_note",
           "getsockopt value: the request capped at net.core.rmem_max, then doubled by the kernel for its overhead"},
          {"threads_pinned_to_cpus", pinned ? Json{placement.first, placement.second} : Json::array()},
          {"shared_machine", "other work runs on these cores: expect noise, compare medians across runs"}};
}

Json latency_json(const LatencySamples& s, std::size_t round_trips, Placement placement, int fifo_priority) {
  const auto raw = summary(s.raw_one_way_us);
  const auto path = summary(s.path_one_way_us);
  const double added_p50 = path["p50"].get<double>() - raw["p50"].get<double>();
  const double added_p99 = path["p99"].get<double>() - raw["p99"].get<double>();
  return {
      {"round_trips_per_variant", round_trips},
      {"order", fmt::format("blocks of {} round trips, A B B A (raw, path, path, raw, ...), after a warm-up", kBlock)},
      {"threads", s.pinned ? fmt::format("two threads, pinned to CPUs {} and {}", placement.first, placement.second)
                           : std::string("two threads, not pinned (fewer than two CPUs, or pinning refused)")},
      {"scheduling", s.fifo ? fmt::format("SCHED_FIFO priority {} (--fifo)", fifo_priority)
                     : fifo_priority > 0
                         ? std::string("SCHED_OTHER: --fifo was refused (needs CAP_SYS_NICE)")
                         : std::string("SCHED_OTHER (default); --fifo N removes other work from the tail")},
      {"clock", "steady_clock (CLOCK_MONOTONIC); one-way = RTT / 2"},
      {"raw_baseline",
       fmt::format("sendto/recvfrom of a {}-byte payload (the size of an encoded 1-frame datagram) on 127.0.0.1, "
                   "echoed back unchanged; both sides wait in poll() before recvfrom",
                   kOneFrameSize)},
      {"path",
       "Datagram of 1 CAN frame (dlc 8) built, encode (HMAC-SHA-512/256), sendto; recvfrom, source address check, "
       "decode (verify), site check, ReplayWindow::accept; the echo side answers with a newly encoded datagram"},
      {"one_way_us", {{"raw", raw}, {"path", path}}},
      {"added_us", {{"p50", added_p50}, {"p99", added_p99}, {"note", "path percentile minus raw percentile"}}},
      {"lost_round_trips", s.lost_round_trips},
      {"goal", "added p99 < 50 us"},
      {"goal_met", added_p99 < 50.0},
  };
}

Json throughput_json(const std::vector<RateRun>& paced, const RateRun& unpaced, double seconds) {
  Json runs = Json::array();
  double sustained = 0;
  for (const auto& run : paced) {
    runs.push_back(to_json(run));
    if (run.clean() && run.sender_kept_up()) sustained = std::max(sustained, run.target);
  }
  return {
      {"frames_per_datagram", 1},
      {"datagram_bytes", kOneFrameSize},
      {"seconds_per_run", seconds},
      {"sender", "one thread, absolute schedule (clock_nanosleep, then spin), encode + sendto per frame"},
      {"receiver",
       "one thread like the bridge's poll loop before its relay threads: poll, drain recvfrom, source check, decode, "
       "site check, replay window"},
      {"direction", "one direction per run; a bridge pair carries the same load each way on separate hosts"},
      {"paced", runs},
      {"unpaced", to_json(unpaced)},
      {"sustained_frames_per_s_without_loss", sustained},
      {"sustained_note",
       "the highest tried rate with no loss and the schedule met; a floor, not the ceiling: see unpaced"},
      {"goal", "at least 20000 frames/s each way without loss (twice a saturated 1 Mbit/s CAN bus)"},
      {"goal_met", sustained >= 20000.0}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Latency, sustained rate and codec cost of the lever-bridge datagram path on loopback; prints JSON."};
  app.name("lever-bench-bridge");
  std::size_t round_trips = 20000;
  std::vector<double> rates{20000, 40000, 80000};
  double seconds = 2.0;
  app.add_option("--round-trips", round_trips, "measured round trips per latency variant (after a warm-up)")
      ->check(CLI::Range(std::size_t{100}, std::size_t{10000000}))
      ->default_str("20000");
  app.add_option("--rates", rates, "target frame rates of the paced runs, frames/s, comma separated")
      ->delimiter(',')
      ->check(CLI::Range(100.0, 10000000.0))
      ->default_str("20000,40000,80000");
  app.add_option("--seconds", seconds, "duration of each rate run")->check(CLI::Range(0.1, 600.0))->default_str("2");
  int fifo_priority = 0;
  app.add_option("--fifo", fifo_priority, "SCHED_FIFO priority for the two latency threads (0: normal scheduling)")
      ->check(CLI::Range(0, 99))
      ->default_str("0");
  CLI11_PARSE(app, argc, argv);

  try {
    const auto raw_key = lb::generate_key();
    const lb::MacKey key(raw_key);  // as the bridge keeps it
    const auto cpus = allowed_cpus();
    const auto placement = choose_cpus(cpus);
    Link a, b;
    open_link(a);
    open_link(b);

    const auto codec = measure_codec(key);
    const auto codec_one_shot = measure_codec(raw_key);
    const auto latency = measure_latency(a, b, key, placement, round_trips, fifo_priority);
    if (latency.lost_round_trips > kMaxLostRoundTrips) {
      fmt::print(stderr, "lever-bench-bridge: more than {} round trips lost on loopback; giving up\n",
                 kMaxLostRoundTrips);
      return 1;
    }
    std::vector<RateRun> paced;
    for (const double rate : rates) paced.push_back(run_rate(key, placement, rate, seconds));
    const auto unpaced = run_rate(key, placement, 0.0, seconds);

    const Json out{
        {"machine", machine_json(cpus, placement, latency.pinned, b.rcvbuf_granted)},
        {"latency", latency_json(latency, round_trips, placement, fifo_priority)},
        {"throughput", throughput_json(paced, unpaced, seconds)},
        {"codec_ns",
         {{"encode_median", codec.encode_ns},
          {"decode_median", codec.decode_ns},
          {"encode_one_shot_median", codec_one_shot.encode_ns},
          {"decode_one_shot_median", codec_one_shot.decode_ns},
          {"calls_each", codec.calls},
          {"note",
           "1-frame datagram, tight loop, no I/O; median of batches of 100 calls, per call; one_shot: the "
           "key's HMAC blocks hashed every call instead of once (MacKey)"}}},
    };
    fmt::print("{}\n", out.dump(2));
  } catch (const SetupError& e) {
    fmt::print(stderr, "lever-bench-bridge: cannot open a UDP socket on 127.0.0.1: {}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "lever-bench-bridge: {}\n", e.what());
    return 1;
  }
  return 0;
}
