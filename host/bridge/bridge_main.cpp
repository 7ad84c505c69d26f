// lever-bridge: joins a lever CAN bus to a remote site over UDP, authenticated, recorded and measured.
#include <fmt/format.h>
#include <sodium.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "allow_list.hpp"
#include "bridge_config.hpp"
#include "key.hpp"
#include "lever/program/config_schema.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"
#include "relay.hpp"
#include "shown_value.hpp"

namespace {

using namespace lever::bridge;
constexpr int kBadInput = lever::program::kBadInput;
constexpr int kRuntimeFailure = 1;

// Whatever a message echoes (an interface name may hold any byte the kernel allows), no control byte reaches the
// terminal.
int fail(int code, std::string message) {
  for (auto& c : message)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = '?';
  fmt::print(stderr, "lever-bridge: {}\n", message);
  return code;
}

// --insecure: everyone can compute this key, so the tag proves nothing. It exists for debugging only.
Key insecure_key() {
  Key k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<std::uint8_t>(0xA5 ^ i);
  return k;
}

// keygen --out: a path the user named that cannot be a new key file is bad input; the rest is the machine's.
bool is_path_mistake(int error) {
  return error == EEXIST || error == ENOENT || error == ENOTDIR || error == EISDIR || error == ELOOP ||
         error == ENAMETOOLONG;
}

int keygen(const std::string& out) {
  try {
    const Key key = generate_key();
    if (out.empty() || out == "-") {
      fmt::print("{}", format_key(key));
      return std::fflush(stdout) == 0 ? 0 : fail(kRuntimeFailure, "keygen: cannot write to stdout");
    }
    write_key_file(out, key);
    fmt::print(stderr, "lever-bridge: wrote a new key to {} (mode 0600); copy it to the other end\n", out);
    return 0;
  } catch (const KeyError& e) {
    return fail(is_path_mistake(e.error_number()) ? kBadInput : kRuntimeFailure, e.what());
  }
}

// What the command line says; each option left out leaves the configuration file's value (or the default).
struct CommandLine {
  std::string config_file;
  std::optional<std::string> can, bind, peer, key_file, allow, record, get_key;
  std::optional<int> site_id, peer_site_id, realtime_priority;
  bool stats_json = false, insecure = false, check_only = false;
  CLI::App* keygen = nullptr;
  std::string keygen_out;
};

void add_options(CLI::App& app, CommandLine& o) {
  lever::program::describe(app, "lever-bridge");  // --version; the footer below says more
  app.footer(
      "Exit status: 0 success (also after SIGINT, SIGTERM or SIGHUP); 1 runtime failure (the CAN interface, the\n"
      "socket, the recording); 2 bad input (an option, the configuration file, the key file,\n"
      "keygen --out naming an existing file or a missing directory).");
  app.add_option("--config", o.config_file,
                 "TOML file with any of the options below as keys (the command line wins); relative paths in it "
                 "are relative to the file");
  app.add_option("--can", o.can, "SocketCAN interface, e.g. can0 or vcan0");
  app.add_option("--bind", o.bind, "local UDP address, HOST:PORT or [IPv6]:PORT");
  app.add_option("--peer", o.peer, "the other bridge's UDP address (one unicast address)");
  app.add_option("--key", o.key_file, "pre-shared key file (64 hex digits, mode 0600; see keygen)");
  app.add_option("--allow", o.allow,
                 "CAN ids allowed in both directions, hex ids and ranges: 0x100-0x1FF,0x700 "
                 "(default: the lever protocol's ids)");
  app.add_option("--record", o.record, "record every frame both ways to this candump -L log file");
  app.add_flag("--stats-json", o.stats_json, "print a JSON line of statistics every second");
  app.add_option("--site-id", o.site_id, "this end's id in datagrams, 0-255 (default random)")
      ->check(lever::program::whole(0, 255));
  app.add_option("--peer-site-id", o.peer_site_id,
                 "the peer's site id, 0-255: datagrams carrying another are refused (default: any but our own)")
      ->check(lever::program::whole(0, 255));
  app.add_flag("--insecure", o.insecure, "no authentication (a public key): for debugging only");
  app.add_option("--realtime-priority", o.realtime_priority,
                 "SCHED_FIFO priority of the two relay threads, with memory locked (default 40; 0: normal "
                 "scheduling); where the system refuses it, one warning and normal scheduling")
      ->check(lever::program::whole(0, 99));
  app.add_flag("--check-config", o.check_only,
               "check the options, the configuration file and the key, print the result and exit (0 valid, 2 "
               "not); opens no CAN interface and no socket");
  app.add_option("--get", o.get_key,
                 "check as --check-config does and print one configuration key's effective value, the file's or the "
                 "command line's (a string without its quotes, an unset one as an empty line): --get peer")
      ->excludes("--check-config");
  o.keygen = app.add_subcommand(
      "keygen", "make a new random key: with --out, a new file of mode 0600 (never overwriting one); else stdout");
  o.keygen->add_option("--out", o.keygen_out, "the key file to create ('-': stdout)");
  app.require_subcommand(0, 1);
}

// The command line over the configuration file, validated. Throws std::invalid_argument (and the key file's
// errors) with the message to show; every such problem is bad input.
BridgeConfig resolve(const CommandLine& o) {
  BridgeConfig config;
  if (!o.config_file.empty()) load_config_file(o.config_file, config);
  auto bad = [](std::string message) { return std::invalid_argument(std::move(message)); };
  if (o.can) config.can_interface = *o.can;
  if (o.bind) config.bind = *o.bind;
  if (o.peer) config.peer = *o.peer;
  if (o.key_file) {
    if (o.key_file->empty()) throw bad("--key: the path is empty");
    config.key_file = *o.key_file;
  }
  if (o.allow) {
    try {
      config.allow_to_network = config.allow_from_network = AllowList::parse(*o.allow);
    } catch (const std::invalid_argument& e) {
      throw bad(fmt::format("--allow: {}", e.what()));
    }
  }
  if (o.record) {
    if (o.record->empty()) throw bad("--record: the path is empty");
    config.record = *o.record;
  }
  if (o.site_id) config.site_id = static_cast<std::uint8_t>(*o.site_id);
  if (o.peer_site_id) config.peer_site_id = static_cast<std::uint8_t>(*o.peer_site_id);
  if (o.realtime_priority) config.realtime_priority = *o.realtime_priority;
  config.stats_json = config.stats_json || o.stats_json;
  config.insecure = o.insecure;  // only ever from the command line, where it is explicit
  validate(config);
  if (config.record && !o.config_file.empty()) {
    std::error_code ec;
    if (std::filesystem::equivalent(*config.record, o.config_file, ec))
      throw bad(fmt::format("record '{}' is the configuration file", shown_value(config.record->string())));
  }
  if (config.insecure && !config.key_file.empty()) throw bad("--insecure and --key exclude each other");
  if (!config.insecure && config.key_file.empty()) throw bad("--key is required (or --insecure, for debugging)");
  return config;
}

// --get KEY: what scripts read a configuration with, so that none parses TOML of its own.
int print_key(BridgeConfig config, const std::string& key) {
  const auto schema = schema_for(config);
  const auto value = schema.value_text(key);
  if (!value) {
    std::string keys;
    for (const auto& k : schema.keys("")) keys += (keys.empty() ? "" : ", ") + k;
    return fail(kBadInput, fmt::format("--get: no key '{}'; the keys: {}", lever::program::printable(key), keys));
  }
  fmt::print("{}\n", *value);
  return 0;
}

// The key the configuration names, or with --insecure the public one, said loudly.
Key key_for(const BridgeConfig& config) {
  if (!config.insecure) return load_key_file(config.key_file);
  fmt::print(stderr,
             "lever-bridge: WARNING: --insecure: datagrams are not authenticated; anyone who can reach {} can put "
             "frames on {}\n",
             config.bind, config.can_interface);
  return insecure_key();
}

// SIGINT, SIGTERM and SIGHUP are taken by the relay's signalfd: blocked before any thread (the recorder's) starts.
void block_stop_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Relays CAN frames between a SocketCAN interface and a peer lever-bridge over UDP (IPv4 or IPv6). Every\n"
      "frame goes out at once, authenticated with HMAC-SHA-512/256 under a pre-shared key; datagrams from other\n"
      "addresses, forged, tampered, replayed or sent before this bridge started are dropped and counted; an\n"
      "allow-list per direction keeps other ids off both sides. SIGINT, SIGTERM and SIGHUP flush the recording\n"
      "and exit 0."};
  CommandLine options;
  add_options(app, options);
  if (const auto stop = lever::program::parse(app, argc, argv)) return *stop;
  if (sodium_init() < 0) return fail(kRuntimeFailure, "libsodium failed to initialize");
  if (options.keygen->parsed()) return keygen(options.keygen_out);

  BridgeConfig config;
  Key key;
  try {
    config = resolve(options);
    key = key_for(config);
  } catch (const std::exception& e) {
    return fail(kBadInput, e.what());
  }
  if (options.get_key) return print_key(config, *options.get_key);
  if (options.check_only) {
    fmt::print("lever-bridge: configuration valid: {} <-> {} -> {}, key {}, allow to network {}, from network {}\n",
               config.can_interface, config.bind, config.peer,
               config.insecure ? "(insecure)" : config.key_file.string(), config.allow_to_network.describe(),
               config.allow_from_network.describe());
    return 0;
  }

  block_stop_signals();
  Relay relay;
  std::string error;
  if (!relay.start(config, key, error)) return fail(kRuntimeFailure, error);
  fmt::print(stderr, "lever-bridge: {} <-> {} -> {} (allow to network {}, from network {})\n", config.can_interface,
             config.bind, config.peer, config.allow_to_network.describe(), config.allow_from_network.describe());
  return relay.run();
}
