// lever-bridge: joins a lever CAN bus to a remote site over UDP, authenticated, recorded and measured.
#include <fmt/format.h>
#include <sched.h>
#include <sodium.h>
#include <sys/mman.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>

#include "allow_list.hpp"
#include "bridge_config.hpp"
#include "key.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"
#include "relay.hpp"

namespace {

using namespace lever::bridge;
constexpr int kBadInput = lever::program::kBadInput;

int fail(int code, const std::string& message) {
  fmt::print(stderr, "lever-bridge: {}\n", message);
  return code;
}

// --insecure: everyone can compute this key, so the tag proves nothing. It exists for debugging only.
Key insecure_key() {
  Key k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<std::uint8_t>(0xA5 ^ i);
  return k;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Relays CAN frames between a SocketCAN interface and a peer lever-bridge over UDP (IPv4 or IPv6). Every\n"
      "frame goes out at once, authenticated with HMAC-SHA-512/256 under a pre-shared key; datagrams from other\n"
      "addresses, forged, tampered or replayed ones are dropped and counted; an allow-list per direction keeps\n"
      "other ids off both sides. SIGINT/SIGTERM flush the recording and exit 0."};
  lever::program::describe(app, "lever-bridge");
  BridgeConfig config;
  std::string config_file, allow, record;
  std::optional<int> site_id;
  int realtime_priority = 0;
  app.add_option("--config", config_file, "TOML file with any of the options below (the command line wins)");
  app.add_option("--can", config.can_interface, "SocketCAN interface, e.g. can0 or vcan0");
  app.add_option("--bind", config.bind, "local UDP address, HOST:PORT or [IPv6]:PORT");
  app.add_option("--peer", config.peer, "the other bridge's UDP address");
  app.add_option("--key", config.key_file, "pre-shared key file (64 hex digits, mode 0600; see keygen)");
  app.add_option("--allow", allow,
                 "CAN ids allowed in both directions, hex ids and ranges: 0x100-0x1FF,0x700 "
                 "(default: the lever protocol's ids)");
  app.add_option("--record", record, "record every frame both ways to this candump -L log file");
  app.add_flag("--stats-json", config.stats_json, "print a JSON line of statistics every second");
  app.add_option("--site-id", site_id, "this end's id in datagrams, 0-255 (default random)")
      ->check(lever::program::whole(0, 255));
  app.add_flag("--insecure", config.insecure, "no authentication (a public key): for debugging only");
  app.add_option("--realtime-priority", realtime_priority,
                 "run the relay under SCHED_FIFO at this priority (1-99) with memory locked; on a busy host "
                 "this is what keeps the latency tail short")
      ->check(lever::program::whole(1, 99));
  auto* keygen = app.add_subcommand("keygen", "print a new random key in the key file format");
  app.require_subcommand(0, 1);

  if (const auto stop = lever::program::parse(app, argc, argv)) return *stop;
  if (sodium_init() < 0) return fail(1, "libsodium failed to initialize");
  if (keygen->parsed()) {
    fmt::print("{}", format_key(generate_key()));
    return 0;
  }

  Key key;
  try {
    if (!config_file.empty()) {
      BridgeConfig from_file;
      load_config_file(config_file, from_file);
      // The command line overrides the file: re-apply what was given on it.
      BridgeConfig cli = config;
      config = from_file;
      if (!cli.can_interface.empty()) config.can_interface = cli.can_interface;
      if (!cli.bind.empty()) config.bind = cli.bind;
      if (!cli.peer.empty()) config.peer = cli.peer;
      if (!cli.key_file.empty()) config.key_file = cli.key_file;
      config.stats_json = config.stats_json || cli.stats_json;
      config.insecure = cli.insecure;  // only ever from the command line, where it is explicit
    }
    if (!allow.empty()) config.allow_to_network = config.allow_from_network = AllowList::parse(allow);
    if (!record.empty()) config.record = record;
    if (site_id) config.site_id = static_cast<std::uint8_t>(*site_id);
    for (const auto& [value, name] :
         {std::pair{&config.can_interface, "--can"}, {&config.bind, "--bind"}, {&config.peer, "--peer"}})
      if (value->empty()) return fail(kBadInput, fmt::format("{} is required (see --help)", name));
    if (config.insecure) {
      if (!config.key_file.empty()) return fail(kBadInput, "--insecure and --key exclude each other");
      fmt::print(stderr,
                 "lever-bridge: WARNING: --insecure: datagrams are not authenticated; anyone who can reach {} can "
                 "put frames on {}\n",
                 config.bind, config.can_interface);
      key = insecure_key();
    } else {
      if (config.key_file.empty()) return fail(kBadInput, "--key is required (or --insecure, for debugging)");
      key = load_key_file(config.key_file);
    }
  } catch (const std::exception& e) {
    return fail(kBadInput, e.what());
  }

  // SIGINT and SIGTERM are taken by the relay's signalfd; block them before any thread (the recorder's) starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  Relay relay;
  std::string error;
  if (!relay.start(config, key, error)) return fail(1, error);
  if (realtime_priority > 0) {
    // The recorder's writer thread started before this and keeps the normal policy: only the relay is real time.
    const sched_param param{realtime_priority};
    if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0 || ::mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
      return fail(1, fmt::format("--realtime-priority {}: {} (needs root or CAP_SYS_NICE and CAP_IPC_LOCK)",
                                 realtime_priority, std::strerror(errno)));
  }
  fmt::print(stderr, "lever-bridge: {} <-> {} -> {} (allow to network {}, from network {})\n", config.can_interface,
             config.bind, config.peer, config.allow_to_network.describe(), config.allow_from_network.describe());
  return relay.run();
}
