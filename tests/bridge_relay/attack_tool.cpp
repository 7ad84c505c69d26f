// lever-bridge-attack: sends crafted datagrams at a bridge, for the kernel-rig tests. Each kind of attack
// carries frames with a distinct id (0x101 + kind), so a test can tell from candump which ones got through.
#include <fmt/format.h>
#include <sodium.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <map>
#include <vector>

#include "datagram.hpp"
#include "key.hpp"
#include "lever/platform/udp_socket.hpp"

namespace {

using namespace lever;
using namespace lever::bridge;

enum class Attack { valid, forged, tampered, replayed, truncated, oversized, reflected, garbage };

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Sends crafted lever-bridge datagrams (for tests)."};
  app.name("lever-bridge-attack");
  std::string key_file, from, to;
  Attack attack = Attack::valid;
  int count = 10;
  std::uint64_t sequence = 1;
  int sender = 77;
  const std::map<std::string, Attack> kinds{{"valid", Attack::valid},         {"forged", Attack::forged},
                                            {"tampered", Attack::tampered},   {"replayed", Attack::replayed},
                                            {"truncated", Attack::truncated}, {"oversized", Attack::oversized},
                                            {"reflected", Attack::reflected}, {"garbage", Attack::garbage}};
  app.add_option("--key", key_file, "the bridges' key file")->required();
  app.add_option("--from", from, "local address to send from")->required();
  app.add_option("--to", to, "the bridge's address")->required();
  app.add_option("--kind", attack, "valid, forged, tampered, replayed, truncated, oversized, reflected, garbage")
      ->transform(CLI::CheckedTransformer(kinds))
      ->required();
  app.add_option("--count", count, "datagrams")->check(CLI::Range(1, 1000000));
  app.add_option("--sequence", sequence, "first sequence number");
  app.add_option("--sender", sender, "site id written in the datagrams (reflected: the bridge's own)");
  CLI11_PARSE(app, argc, argv);
  if (sodium_init() < 0) return 1;

  std::string error;
  const auto local = platform::parse_socket_address(from, error);
  const auto remote = platform::parse_socket_address(to, error);
  if (!local || !remote) {
    fmt::print(stderr, "lever-bridge-attack: {}\n", error);
    return 2;
  }
  auto opened = platform::UdpSocket::open(*local);
  if (!opened) {
    fmt::print(stderr, "lever-bridge-attack: {}\n", opened.error().message);
    return 1;
  }
  auto& socket = opened.value();
  const Key key = load_key_file(key_file);
  const Key wrong = generate_key();

  std::array<std::uint8_t, 2048> buffer{};
  std::vector<std::uint8_t> first_valid;
  int sent = 0;
  for (int i = 0; i < count; ++i) {
    Datagram d;
    d.sender = static_cast<std::uint8_t>(sender);
    d.sequence = sequence + static_cast<std::uint64_t>(i);
    d.timestamp_us = 1;
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
    if (socket.send_to(std::span(buffer.data(), size), *remote) == platform::UdpStatus::ok) ++sent;
    ::usleep(1000);  // a 1 kHz stream, and no pressure on the receive buffer
  }
  fmt::print("{} {} datagrams sent\n", sent, app.get_option("--kind")->as<std::string>());
  return 0;
}
