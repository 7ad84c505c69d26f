// lever-bridge-attack: sends crafted datagrams at a bridge, for the kernel-rig tests. Each kind of attack
// carries frames with a distinct id (0x101 + kind), so a test can tell from candump which ones got through.
// Two more kinds are an attacker on the path: `proxy` relays between two bridges and records what one sends the
// other; `replay-capture` sends such a recording again, byte for byte.
#include <fmt/format.h>
#include <poll.h>
#include <sodium.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <map>
#include <vector>

#include "datagram.hpp"
#include "key.hpp"
#include "lever/board/udp_socket.hpp"

namespace {

using namespace lever;
using namespace lever::bridge;

enum class Attack {
  valid,
  forged,
  tampered,
  replayed,
  truncated,
  oversized,
  reflected,
  garbage,
  proxy,
  replay_capture
};

// The bridge's epoch, learned as a peer learns it: a probe request from our address, whose reply carries it (a
// bridge answers probes that do not echo its epoch; that is how a restarted peer catches up). 0 when no reply came.
std::uint64_t learn_epoch(board::UdpSocket& socket, const board::SocketAddress& bridge, const Key& key,
                          std::uint8_t sender, std::uint64_t sequence, std::uint64_t own_epoch) {
  Datagram probe;
  probe.kind = Kind::probe_request;
  probe.sender = sender;
  probe.sequence = sequence;
  probe.timestamp_us = 1;
  probe.epoch = own_epoch;
  std::array<std::uint8_t, kMaxDatagramSize + 1> buffer{};
  const auto encoded = encode(probe, key, buffer);
  if (!encoded || socket.send_to(std::span(buffer.data(), encoded.size), bridge) != board::UdpStatus::ok) return 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd fd{socket.fd(), POLLIN, 0};
    if (::poll(&fd, 1, 100) <= 0) continue;
    std::size_t size = 0;
    board::SocketAddress from;
    if (socket.receive(buffer, size, from) != board::UdpStatus::ok || !(from == bridge)) continue;
    Datagram reply;
    if (size <= kMaxDatagramSize && decode(std::span(buffer.data(), size), key, reply) == WireError::none &&
        reply.peer_epoch == own_epoch) {
      return reply.epoch;
    }
  }
  return 0;
}

// proxy: a bridge A sends to `listen`, and we pass it on to the bridge B at `to` from `from` (B's configured peer);
// B's datagrams to `from` go back to A at `back` from `listen`. What A sends B is appended to `capture` as records
// of a 2-byte big-endian length and the datagram.
int run_proxy(board::UdpSocket& b_side, const board::SocketAddress& b, const std::string& listen,
              const std::string& back, const std::string& capture, double duration_s) {
  std::string error;
  const auto listen_address = board::parse_socket_address(listen, error);
  const auto a = board::parse_socket_address(back, error);
  if (!listen_address || !a) {
    fmt::print(stderr, "lever-bridge-attack: proxy needs --listen and --back: {}\n", error);
    return 2;
  }
  auto opened = board::UdpSocket::open(*listen_address);
  if (!opened) {
    fmt::print(stderr, "lever-bridge-attack: {}\n", opened.error().message);
    return 1;
  }
  auto& a_side = opened.value();
  std::FILE* file = capture.empty() ? nullptr : std::fopen(capture.c_str(), "wb");
  if (!capture.empty() && !file) {
    fmt::print(stderr, "lever-bridge-attack: cannot write {}\n", capture);
    return 1;
  }
  std::array<std::uint8_t, 2048> buffer{};
  int forwarded = 0, captured = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
  while (std::chrono::steady_clock::now() < end) {
    pollfd fds[2] = {{a_side.fd(), POLLIN, 0}, {b_side.fd(), POLLIN, 0}};
    if (::poll(fds, 2, 50) <= 0) continue;
    std::size_t size = 0;
    board::SocketAddress from;
    if ((fds[0].revents & POLLIN) && a_side.receive(buffer, size, from) == board::UdpStatus::ok &&
        size <= buffer.size()) {
      b_side.send_to(std::span(buffer.data(), size), b);
      ++forwarded;
      if (file) {
        const std::uint8_t length[2] = {static_cast<std::uint8_t>(size >> 8), static_cast<std::uint8_t>(size)};
        std::fwrite(length, 1, 2, file);
        std::fwrite(buffer.data(), 1, size, file);
        std::fflush(file);
        ++captured;
      }
    }
    if ((fds[1].revents & POLLIN) && b_side.receive(buffer, size, from) == board::UdpStatus::ok &&
        size <= buffer.size()) {
      a_side.send_to(std::span(buffer.data(), size), *a);
      ++forwarded;
    }
  }
  if (file) std::fclose(file);
  fmt::print("proxy: {} datagrams forwarded, {} captured\n", forwarded, captured);
  return 0;
}

int replay_capture(board::UdpSocket& socket, const board::SocketAddress& to, const std::string& capture) {
  std::FILE* file = std::fopen(capture.c_str(), "rb");
  if (!file) {
    fmt::print(stderr, "lever-bridge-attack: cannot read {}\n", capture);
    return 2;
  }
  std::array<std::uint8_t, 2048> buffer{};
  int sent = 0;
  std::uint8_t length[2];
  while (std::fread(length, 1, 2, file) == 2) {
    const std::size_t size = static_cast<std::size_t>(length[0] << 8 | length[1]);
    if (size > buffer.size() || std::fread(buffer.data(), 1, size, file) != size) break;
    if (socket.send_to(std::span(buffer.data(), size), to) == board::UdpStatus::ok) ++sent;
    ::usleep(1000);
  }
  std::fclose(file);
  fmt::print("{} captured datagrams replayed\n", sent);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Sends crafted lever-bridge datagrams (for tests)."};
  app.name("lever-bridge-attack");
  std::string key_file, from, to;
  Attack attack = Attack::valid;
  int count = 10;
  std::uint64_t sequence = 1;
  int sender = 77;
  const std::map<std::string, Attack> kinds{
      {"valid", Attack::valid},         {"forged", Attack::forged},
      {"tampered", Attack::tampered},   {"replayed", Attack::replayed},
      {"truncated", Attack::truncated}, {"oversized", Attack::oversized},
      {"reflected", Attack::reflected}, {"garbage", Attack::garbage},
      {"proxy", Attack::proxy},         {"replay-capture", Attack::replay_capture}};
  std::string listen, back, capture;
  double duration_s = 10;
  int probe_sender = 77;
  app.add_option("--key", key_file, "the bridges' key file (all kinds but proxy and replay-capture)");
  app.add_option("--from", from, "local address to send from")->required();
  app.add_option("--to", to, "the bridge's address")->required();
  app.add_option("--kind", attack,
                 "valid, forged, tampered, replayed, truncated, oversized, reflected, garbage; proxy, replay-capture")
      ->transform(CLI::CheckedTransformer(kinds))
      ->required();
  app.add_option("--count", count, "datagrams")->check(CLI::Range(1, 1000000));
  app.add_option("--sequence", sequence, "first sequence number");
  app.add_option("--sender", sender, "site id written in the datagrams (reflected: the bridge's own)");
  app.add_option("--probe-sender", probe_sender, "site id of the probe that learns the bridge's epoch");
  app.add_option("--listen", listen, "proxy: the address bridge A sends to");
  app.add_option("--back", back, "proxy: bridge A's address");
  app.add_option("--capture", capture, "proxy: record A's datagrams here; replay-capture: send them again");
  app.add_option("--duration", duration_s, "proxy: seconds to run")->check(CLI::Range(0.1, 3600.0));
  CLI11_PARSE(app, argc, argv);
  if (sodium_init() < 0) return 1;

  std::string error;
  const auto local = board::parse_socket_address(from, error);
  const auto remote = board::parse_socket_address(to, error);
  if (!local || !remote) {
    fmt::print(stderr, "lever-bridge-attack: {}\n", error);
    return 2;
  }
  auto opened = board::UdpSocket::open(*local);
  if (!opened) {
    fmt::print(stderr, "lever-bridge-attack: {}\n", opened.error().message);
    return 1;
  }
  auto& socket = opened.value();
  if (attack == Attack::proxy) return run_proxy(socket, *remote, listen, back, capture, duration_s);
  if (attack == Attack::replay_capture) return replay_capture(socket, *remote, capture);
  if (key_file.empty()) {
    fmt::print(stderr, "lever-bridge-attack: --kind {} needs --key\n", app.get_option("--kind")->as<std::string>());
    return 2;
  }
  const Key key = load_key_file(key_file);
  const Key wrong = generate_key();
  // Datagrams that are to pass as fresh echo the bridge's epoch, as the real peer's do.
  const std::uint64_t own_epoch = generate_epoch();
  const std::uint64_t bridge_epoch =
      attack == Attack::garbage || attack == Attack::forged
          ? 0
          : learn_epoch(socket, *remote, key, static_cast<std::uint8_t>(probe_sender), sequence - 1, own_epoch);

  std::array<std::uint8_t, 2048> buffer{};
  std::vector<std::uint8_t> first_valid;
  int sent = 0;
  for (int i = 0; i < count; ++i) {
    Datagram d;
    d.sender = static_cast<std::uint8_t>(sender);
    d.sequence = sequence + static_cast<std::uint64_t>(i);
    d.timestamp_us = 1;
    d.epoch = own_epoch;
    d.peer_epoch = bridge_epoch;
    d.frame_count = 1;
    d.frames[0] = {0x101u + static_cast<std::uint32_t>(attack), 8, {}};
    d.frames[0].data[0] = static_cast<std::uint8_t>(i);
    const auto encoded = encode(d, attack == Attack::forged ? wrong : key, buffer);
    if (!encoded) return 1;
    std::size_t size = encoded.size;
    switch (attack) {
      case Attack::tampered:
        buffer[kHeaderSize + 3] ^= 0x01;  // one bit of the first frame's data
        break;
      case Attack::replayed:
        // The first datagram is genuine; every later one repeats its bytes exactly.
        if (first_valid.empty()) first_valid.assign(buffer.begin(), buffer.begin() + static_cast<long>(size));
        std::copy(first_valid.begin(), first_valid.end(), buffer.begin());
        size = first_valid.size();
        break;
      case Attack::truncated:
        size = static_cast<std::size_t>(i) % size;  // every length short of the whole
        break;
      case Attack::oversized:
        size = kMaxDatagramSize + 1 + static_cast<std::size_t>(i) % 1000;
        break;
      case Attack::garbage:
        size = 1 + randombytes_uniform(1500);
        randombytes_buf(buffer.data(), size);
        break;
      default:
        break;
    }
    if (socket.send_to(std::span(buffer.data(), size), *remote) == board::UdpStatus::ok) ++sent;
    ::usleep(1000);  // a 1 kHz stream, and no pressure on the receive buffer
  }
  fmt::print("{} {} datagrams sent\n", sent, app.get_option("--kind")->as<std::string>());
  return 0;
}
