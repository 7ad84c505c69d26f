// lever-bench-relay-floor: the smallest user-space relay that makes lever-bridge's hops, as a floor for its latency
// (scripts/bench-bridge, variants floor and floor-hmac). Two processes:
//
//   can-to-udp   recvmmsg(MSG_WAITFORONE) on a CAN raw socket; every frame there when it wakes goes out in a UDP
//                datagram of its own (its 16 bytes as the kernel gave them), all with one sendmmsg.
//   udp-to-can   recvmmsg(MSG_WAITFORONE) on a UDP socket; the frames of every datagram there, written with one
//                sendmmsg on a CAN raw socket.
//
// No authentication, no recorder, no statistics, no clock reading, no allow-list: only the hops. With --hmac both
// ends do what the bridge does to a datagram and nothing more, to price it: the sender puts all the frames of a
// wake-up into one lever-bridge datagram (docs/datagram-format.md) and encodes it with the precomputed key state;
// the receiver decodes it (verifying the tag) and writes its frames. SCHED_FIFO and mlockall as lever-bridge's
// relay threads have them (priority 40 by default), with one warning where refused. SIGINT and SIGTERM end it
// with a line of counts on stderr.
#include <fmt/format.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <array>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>

#include "datagram.hpp"
#include "key.hpp"
#include "lever/board/udp_socket.hpp"
#include "lever/program/parse.hpp"

namespace {

namespace lb = lever::bridge;
constexpr int kBadInput = lever::program::kBadInput;
constexpr int kRuntimeFailure = 1;
constexpr const char* kName = "lever-bench-relay-floor";

// As many frames per wake-up as the bridge's CAN thread takes (two full datagrams).
constexpr std::size_t kBatch = 2 * lb::kMaxFrames;

volatile std::sig_atomic_t stop_requested = 0;
void on_stop(int) { stop_requested = 1; }

int fail(int code, const std::string& message) {
  fmt::print(stderr, "{}: {}\n", kName, message);
  return code;
}

// A CAN raw socket bound to `interface`, blocking; -1 with `error` set on failure. A socket that only writes
// receives nothing (an empty filter), so that its queue never fills.
int open_can(const std::string& interface, bool write_only, std::string& error) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    error = fmt::format("CAN interface '{}': a name of 1 to {} characters", interface, IFNAMSIZ - 1);
    return -1;
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    error = fmt::format("CAN socket: {} (is the can-raw module loaded?)", std::strerror(errno));
    return -1;
  }
  ifreq request{};
  std::memcpy(request.ifr_name, interface.c_str(), interface.size());
  if (::ioctl(fd, SIOCGIFINDEX, &request) != 0) {
    error = fmt::format("CAN interface '{}': {}", interface, std::strerror(errno));
    ::close(fd);
    return -1;
  }
  if (write_only && ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, nullptr, 0) != 0) {
    error = fmt::format("{}: CAN_RAW_FILTER: {}", interface, std::strerror(errno));
    ::close(fd);
    return -1;
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    error = fmt::format("CAN interface '{}': bind: {}", interface, std::strerror(errno));
    ::close(fd);
    return -1;
  }
  return fd;
}

int open_udp(const lever::board::SocketAddress& local, std::string& error) {
  const int fd = ::socket(local.get()->sa_family, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    error = fmt::format("UDP socket: {}", std::strerror(errno));
    return -1;
  }
  if (local.length != 0 && ::bind(fd, local.get(), local.length) != 0) {
    error = fmt::format("UDP bind: {}", std::strerror(errno));
    ::close(fd);
    return -1;
  }
  return fd;
}

// SCHED_FIFO `priority` for the process and all its memory locked, as lever-bridge's relay threads; 0: neither.
void go_realtime(int priority) {
  if (priority == 0) return;
  std::string refused;
  const rlimit unlimited{RLIM_INFINITY, RLIM_INFINITY};
  ::setrlimit(RLIMIT_MEMLOCK, &unlimited);
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) refused = fmt::format("mlockall: {}", std::strerror(errno));
  const sched_param param{priority};
  if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0)
    refused += fmt::format("{}SCHED_FIFO {}: {}", refused.empty() ? "" : "; ", priority, std::strerror(errno));
  if (!refused.empty())
    fmt::print(stderr, "{}: WARNING: real-time scheduling refused ({}); relaying without it\n", kName, refused);
}

struct Counts {
  std::uint64_t frames = 0, datagrams = 0, lost = 0, rejected = 0;
};

// Sends or writes `count` messages, retrying on EINTR; a message the kernel refuses is counted lost.
void send_all(int fd, std::span<mmsghdr> messages, Counts& counts) {
  std::size_t done = 0;
  while (done < messages.size()) {
    const int n = ::sendmmsg(fd, messages.data() + done, static_cast<unsigned>(messages.size() - done), MSG_DONTWAIT);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (!(n < 0 && errno == EINTR)) {
      ++counts.lost;
      ++done;
    }
  }
}

// ---- can-to-udp ----

int can_to_udp(int can_fd, int udp_fd, const lever::board::SocketAddress& peer, const lb::MacKey* key, Counts& counts) {
  std::array<can_frame, kBatch> raw{};
  std::array<iovec, kBatch> iov{};
  std::array<mmsghdr, kBatch> in{}, out{};
  for (std::size_t i = 0; i < kBatch; ++i) {
    iov[i] = {&raw[i], sizeof raw[i]};
    in[i].msg_hdr.msg_iov = &iov[i];
    in[i].msg_hdr.msg_iovlen = 1;
    // Without --hmac a datagram is the frame's own bytes: the receive buffers go out as they are.
    out[i].msg_hdr.msg_name = const_cast<sockaddr*>(peer.get());
    out[i].msg_hdr.msg_namelen = peer.length;
    out[i].msg_hdr.msg_iov = &iov[i];
    out[i].msg_hdr.msg_iovlen = 1;
  }
  constexpr std::size_t kDatagrams = kBatch / lb::kMaxFrames;
  std::array<lb::Datagram, kDatagrams> datagrams{};
  std::array<std::array<std::uint8_t, lb::kMaxDatagramSize>, kDatagrams> wire{};
  std::array<iovec, kDatagrams> wire_iov{};
  std::uint64_t sequence = 1;

  while (!stop_requested) {
    const int got = ::recvmmsg(can_fd, in.data(), kBatch, MSG_WAITFORONE, nullptr);
    if (got < 0) {
      if (errno == EINTR) continue;
      return fail(kRuntimeFailure, fmt::format("CAN recvmmsg: {}", std::strerror(errno)));
    }
    const auto n = static_cast<std::size_t>(got);
    counts.frames += n;
    if (key == nullptr) {
      send_all(udp_fd, std::span(out.data(), n), counts);
      counts.datagrams += n;
      continue;
    }
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (i % lb::kMaxFrames == 0) {
        lb::Datagram& d = datagrams[count++];
        d.sender = 1;
        d.epoch = 1;
        d.sequence = sequence++;
        d.frame_count = 0;
      }
      lb::Datagram& d = datagrams[count - 1];
      auto& f = d.frames[d.frame_count++];
      f.id = raw[i].can_id & CAN_SFF_MASK;
      f.dlc = raw[i].can_dlc > 8 ? 8 : raw[i].can_dlc;
      std::memcpy(f.data.data(), raw[i].data, 8);
    }
    for (std::size_t k = 0; k < count; ++k) {
      const auto encoded = lb::encode(datagrams[k], *key, wire[k]);
      wire_iov[k] = {wire[k].data(), encoded.size};
      out[k].msg_hdr.msg_iov = &wire_iov[k];
    }
    send_all(udp_fd, std::span(out.data(), count), counts);
    counts.datagrams += count;
  }
  return 0;
}

// ---- udp-to-can ----

int udp_to_can(int udp_fd, int can_fd, const lb::MacKey* key, Counts& counts) {
  // Without --hmac a datagram lands in a can_frame as it is; with it, in a buffer one byte over the largest.
  constexpr std::size_t kUdpBatch = 16;
  std::array<std::array<std::uint8_t, lb::kMaxDatagramSize + 1>, kUdpBatch> buffers{};
  std::array<iovec, kUdpBatch> in_iov{};
  std::array<mmsghdr, kUdpBatch> in{};
  std::array<can_frame, kUdpBatch * lb::kMaxFrames> raw{};
  std::array<iovec, kUdpBatch * lb::kMaxFrames> out_iov{};
  std::array<mmsghdr, kUdpBatch * lb::kMaxFrames> out{};
  for (std::size_t i = 0; i < out.size(); ++i) {
    out_iov[i] = {&raw[i], sizeof raw[i]};
    out[i].msg_hdr.msg_iov = &out_iov[i];
    out[i].msg_hdr.msg_iovlen = 1;
  }
  for (std::size_t i = 0; i < kUdpBatch; ++i) {
    in_iov[i] = key ? iovec{buffers[i].data(), buffers[i].size()} : iovec{&raw[i], sizeof raw[i]};
    in[i].msg_hdr.msg_iov = &in_iov[i];
    in[i].msg_hdr.msg_iovlen = 1;
  }
  lb::Datagram d;

  while (!stop_requested) {
    const int got = ::recvmmsg(udp_fd, in.data(), kUdpBatch, MSG_WAITFORONE | MSG_TRUNC, nullptr);
    if (got < 0) {
      if (errno == EINTR) continue;
      return fail(kRuntimeFailure, fmt::format("UDP recvmmsg: {}", std::strerror(errno)));
    }
    const auto n = static_cast<std::size_t>(got);
    counts.datagrams += n;
    std::size_t frames = 0;
    if (key == nullptr) {
      // Each datagram is one frame, already in place; a wrong size is not a frame.
      for (std::size_t i = 0; i < n; ++i) {
        if (in[i].msg_len != sizeof(can_frame)) {
          ++counts.rejected;
          continue;
        }
        if (frames != i) raw[frames] = raw[i];
        ++frames;
      }
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t size = in[i].msg_len;
        if (size > lb::kMaxDatagramSize ||
            lb::decode(std::span(buffers[i].data(), size), *key, d) != lb::WireError::none) {
          ++counts.rejected;
          continue;
        }
        for (const auto& f : d.frame_list()) {
          can_frame& r = raw[frames++];
          r = {};
          r.can_id = f.id;
          r.can_dlc = f.dlc;
          std::memcpy(r.data, f.data.data(), 8);
        }
      }
    }
    send_all(can_fd, std::span(out.data(), frames), counts);
    counts.frames += frames;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "The smallest relay of lever-bridge's hops, for scripts/bench-bridge: CAN -> UDP in one process (can-to-udp),\n"
      "UDP -> CAN in another (udp-to-can), a frame per datagram; no authentication (unless --hmac), no recorder.\n"
      "SIGINT or SIGTERM ends it with a line of counts on stderr."};
  lever::program::describe(app, kName);
  std::string can, address;
  int priority = 40;
  bool hmac = false;
  auto* sender = app.add_subcommand("can-to-udp", "read CAN frames, send each in a UDP datagram to --peer");
  sender->add_option("--can", can, "the CAN interface to read, e.g. vcan0")->required();
  sender->add_option("--peer", address, "where the datagrams go, HOST:PORT (e.g. 127.0.0.1:5001)")->required();
  auto* receiver = app.add_subcommand("udp-to-can", "receive datagrams on --bind, write their frames to CAN");
  receiver->add_option("--bind", address, "the local UDP address, HOST:PORT (e.g. 127.0.0.1:5001)")->required();
  receiver->add_option("--can", can, "the CAN interface to write, e.g. vcan1")->required();
  for (auto* sub : {sender, receiver}) {
    sub->add_option("--realtime-priority", priority,
                    "SCHED_FIFO priority, with memory locked (default 40; 0: normal scheduling); where refused, one "
                    "warning and normal scheduling")
        ->check(CLI::Range(0, 99));
    sub->add_flag("--hmac", hmac,
                  "lever-bridge datagrams, encoded and verified with a fixed key's precomputed HMAC state (both ends "
                  "must say it)");
  }
  app.require_subcommand(1);
  if (const auto stop = lever::program::parse(app, argc, argv)) return *stop;

  std::string error;
  const auto parsed = lever::board::parse_socket_address(address, error);
  if (!parsed) return fail(kBadInput, fmt::format("{}: {}", sender->parsed() ? "--peer" : "--bind", error));
  std::optional<lb::MacKey> key;
  if (hmac) {
    if (!lb::init_crypto()) return fail(kRuntimeFailure, "libsodium failed to initialize");
    lb::Key k;
    for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<std::uint8_t>(0x5A ^ i);
    key.emplace(k);
  }

  const bool sending = sender->parsed();
  const int can_fd = open_can(can, !sending, error);
  if (can_fd < 0) return fail(kRuntimeFailure, error);
  lever::board::SocketAddress any{};
  any.storage.ss_family = parsed->storage.ss_family;
  const int udp_fd = open_udp(sending ? any : *parsed, error);
  if (udp_fd < 0) return fail(kRuntimeFailure, error);

  // Without SA_RESTART: a signal ends the blocked recvmmsg, and the loop sees the flag. SA_RESETHAND: should one
  // land between the loop's look at the flag and its recvmmsg, a second one ends the process.
  struct sigaction stop {};
  stop.sa_handler = on_stop;
  stop.sa_flags = SA_RESETHAND;
  sigemptyset(&stop.sa_mask);
  ::sigaction(SIGINT, &stop, nullptr);
  ::sigaction(SIGTERM, &stop, nullptr);
  go_realtime(priority);

  Counts counts;
  const lb::MacKey* k = key ? &*key : nullptr;
  const int code = sending ? can_to_udp(can_fd, udp_fd, *parsed, k, counts) : udp_to_can(udp_fd, can_fd, k, counts);
  fmt::print(stderr, "{} {}: {} frames, {} datagrams, {} lost, {} rejected\n", kName,
             sending ? "can-to-udp" : "udp-to-can", counts.frames, counts.datagrams, counts.lost, counts.rejected);
  ::close(udp_fd);
  ::close(can_fd);
  return code;
}
