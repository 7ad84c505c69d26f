#pragma once
// lever-bridge's settings: command line over an optional TOML file over defaults.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "allow_list.hpp"

namespace lever::bridge {

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
  double can_bitrate = 1e6;             // for the bus-load figure
  std::optional<std::uint8_t> site_id;  // default: random at start-up
};

// Reads the TOML file's keys into `config` (the command line is applied afterwards by the caller).
// Throws std::invalid_argument with the file, key and problem.
void load_config_file(const std::filesystem::path& file, BridgeConfig& config);

}  // namespace lever::bridge
