#pragma once
// The status lines a pair's programs print, as lever-view shows them beside the bus: lever-fw's (--stats-json,
// docs/lever-fw.md) carry what no frame does (the TOP's position, the motor torque); lever-bridge's (--stats-json,
// docs/bridge.md) the link's side. Any other line is not a status line and is ignored.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "lever/protocol/messages.hpp"

namespace lever::view {

struct LeverStatus {
  std::uint8_t pair = 0;
  protocol::Role role = protocol::Role::hsi;
  std::string state;
  std::vector<std::string> faults;
  bool position_valid = false;
  std::optional<double> position_rad;
  std::optional<double> velocity_rad_s;
  std::optional<double> force_n;  // its own gauge (the TOP's); null when stale or unused
  std::optional<double> torque_nm;
  std::optional<std::uint64_t> data_sent;
};

struct BridgeStatus {
  std::optional<double> bus_load;
  std::optional<double> to_network_per_s;
  std::optional<double> from_network_per_s;
  std::optional<double> latency_p99_us;
  std::uint64_t sequence_gaps = 0;
  std::uint64_t reordered = 0;
  std::string can;
};

using StatusLine = std::variant<std::monostate, LeverStatus, BridgeStatus>;

// One line of either program's --stats-json; std::monostate for anything else (not JSON, another object, a
// lever line whose role or pair is not the protocol's). Never throws.
StatusLine parse_status_line(std::string_view line);

}  // namespace lever::view
