#pragma once
// lever-bridge's settings: command line over an optional TOML file over defaults, and their validation. Everything
// a user can get wrong is refused here, before any socket is opened, with a message naming the option or key and
// the value (`lever-bridge --check-config` runs exactly this).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "allow_list.hpp"

namespace lever::program {
class ConfigSchema;  // lever/program/config_schema.hpp: only what reads or prints the file needs it
}

namespace lever::bridge {

// The relay threads' SCHED_FIFO priority unless told otherwise: above every ordinary task, below the kernel's
// threaded interrupt handlers (FIFO 50, which deliver the very frames and datagrams the relay waits for) and below
// a lever's own loop (80) and motor guard (81) where a bridge shares a board with lever-fw.
inline constexpr int kDefaultRealtimePriority = 40;

struct BridgeConfig {
  std::string can_interface;
  std::string bind;  // HOST:PORT or [IPv6]:PORT
  std::string peer;
  std::filesystem::path key_file;
  bool insecure = false;  // a publicly known key: no authentication at all, loudly
  AllowList allow_to_network = AllowList::lever_protocol();
  AllowList allow_from_network = AllowList::lever_protocol();
  std::optional<std::filesystem::path> record;
  std::string record_network_interface;   // interface name written for frames from the network ("" = can_interface)
  std::uint64_t record_rotate_bytes = 0;  // 0: never
  int record_keep_files = 5;
  bool stats_json = false;
  double stats_interval_s = 1.0;
  double probe_interval_s = 1.0;
  double can_bitrate = 1e6;                          // for the bus-load figure
  std::optional<std::uint8_t> site_id;               // default: random at start-up
  std::optional<std::uint8_t> peer_site_id;          // when set, datagrams carrying another sender id are refused
  int realtime_priority = kDefaultRealtimePriority;  // the relay threads' SCHED_FIFO priority; 0: normal policy
};

// The configuration file's keys, bound to `config`'s fields: each key's type, range, unit and line of
// documentation, for reading the file and for printing a configuration. Relative paths in the file (key, record)
// are taken from the file's directory, so a configuration can be moved with its key.
program::ConfigSchema schema_for(BridgeConfig& config);

// Reads the TOML file's keys into `config` (the command line is applied afterwards by the caller); on a problem,
// `config` is left as it was. Throws std::invalid_argument: "FILE: KEY: problem", or "FILE:LINE: problem" for
// the TOML syntax.
void load_config_file(const std::filesystem::path& file, BridgeConfig& config);

// The checks that need the whole configuration (file and command line merged): required settings, the interface
// name, the addresses (port 0, a broadcast, multicast or unspecified peer, a peer that is ourselves, mixed
// families) and the site ids. Resolves host names but opens nothing. Throws std::invalid_argument.
void validate(const BridgeConfig& config);

}  // namespace lever::bridge
