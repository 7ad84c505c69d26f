#pragma once
// The once-a-second status line of lever-fw (`--stats-json`), one JSON object per line. docs/lever-fw.md
// documents each field.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "lever/fw/lever.hpp"

namespace lever::app {

// What only a board has (a simulated lever reports null for each).
struct BoardStats {
  std::optional<double> wakeup_p50_us, wakeup_p99_us, wakeup_max_us;
  std::optional<std::uint64_t> minor_faults;
  std::optional<std::uint64_t> modbus_polls, modbus_errors, modbus_timeouts, modbus_reconnects;
};

std::string state_name(protocol::LeverState s);

template <typename Lever>
nlohmann::json stats_line(const Lever& lever, fw::Tick now, const BoardStats& board) {
  const auto& t = lever.telemetry();
  const auto& c = lever.counters();
  nlohmann::json faults = nlohmann::json::array();
  for (const auto f : protocol::kAllFaults)
    if (protocol::has(lever.supervisor().latched(), f)) faults.push_back(std::string(protocol::name(f)));
  const auto& gauge = lever.gauge().state();
  auto optional = [](const auto& v) { return v ? nlohmann::json(*v) : nlohmann::json(); };
  return {
      {"role", lever.config().role == protocol::Role::hsi ? "hsi" : "top"},
      {"pair", lever.config().pair},
      {"state", state_name(lever.supervisor().state())},
      {"faults", faults},
      {"position_rad", t.position_rad},
      {"position_valid", t.position_valid},
      {"velocity_rad_s", t.velocity_rad_s},
      {"force_n", optional(t.force_n)},
      {"force_age_ms", gauge.seen && now >= gauge.last_tick ? nlohmann::json(now - gauge.last_tick) : nlohmann::json()},
      {"remote", optional(t.remote)},
      {"torque_nm", t.torque_nm},
      {"tx_frames", c.tx_frames},
      {"rx_frames", c.rx_frames},
      {"data_sent", c.data_sent},
      {"refresh_sent", c.refresh_sent},
      {"overruns", lever.timing().stats().overruns},
      {"worst_step_interval_ms", lever.timing().stats().worst_interval},
      {"worst_step_us", static_cast<double>(lever.timing().stats().worst_step_ns) * 1e-3},
      {"wakeup_latency_us",
       {{"p50", optional(board.wakeup_p50_us)},
        {"p99", optional(board.wakeup_p99_us)},
        {"max", optional(board.wakeup_max_us)}}},
      {"encoder",
       {{"edges", lever.decoder().edges()},
        {"illegal", lever.decoder().illegal_transitions()},
        {"lost", lever.decoder().lost_edges()}}},
      {"modbus",
       {{"polls", optional(board.modbus_polls)},
        {"errors", optional(board.modbus_errors)},
        {"timeouts", optional(board.modbus_timeouts)},
        {"reconnects", optional(board.modbus_reconnects)}}},
      {"minor_faults", optional(board.minor_faults)},
  };
}

}  // namespace lever::app
