#pragma once
// The once-a-second status line of lever-fw (`--stats-json`), one JSON object per line; docs/lever-fw.md
// documents each field. The loop takes a Snapshot (plain numbers, trivially copyable, so it crosses to the
// printing thread lock-free); the JSON is made outside the loop.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "lever/fw/lever.hpp"

namespace lever::app {

struct Snapshot {
  fw::Tick tick = 0;
  protocol::Role role = protocol::Role::hsi;
  std::uint8_t pair = 0;
  protocol::LeverState state = protocol::LeverState::init;
  protocol::FaultBits faults = 0;
  double position_rad = 0.0;
  bool position_valid = false;
  double velocity_rad_s = 0.0;
  bool has_force = false;
  double force_n = 0.0;
  bool has_force_age = false;
  fw::Tick force_age_ms = 0;
  std::uint32_t force_failed_readings = 0;
  bool has_remote = false;
  double remote = 0.0;
  double torque_nm = 0.0;
  fw::LeverCounters counters{};
  std::uint32_t overruns = 0, long_steps = 0, worst_lost_us = 0;
  fw::Tick worst_interval = 0;
  std::uint64_t worst_step_ns = 0;
  std::uint64_t encoder_edges = 0;
  std::uint32_t encoder_illegal = 0, encoder_lost = 0;
  fw::PassivityMode passivity = fw::PassivityMode::off;
  double dissipated_energy_j = 0.0, observed_energy_j = 0.0;  // since the lever last armed
};

// What only a board has (a simulated lever reports null for each).
struct BoardStats {
  std::optional<double> wakeup_p50_us, wakeup_p99_us, wakeup_max_us;
  std::optional<double> step_p50_us, step_p99_us, step_max_us;  // wake-up to the step's end
  std::optional<std::uint64_t> minor_faults;
  std::optional<std::uint64_t> modbus_polls, modbus_errors, modbus_timeouts, modbus_crc_errors, modbus_exceptions,
      modbus_reconnects;
};

template <typename Lever>
Snapshot snapshot(const Lever& lever, fw::Tick now) noexcept {
  const auto& t = lever.telemetry();
  const auto& gauge = lever.gauge().state();
  Snapshot s;
  s.tick = now;
  s.role = lever.config().role;
  s.pair = lever.config().pair;
  s.state = lever.supervisor().state();
  s.faults = lever.supervisor().latched();
  s.position_rad = t.position_rad;
  s.position_valid = t.position_valid;
  s.velocity_rad_s = t.velocity_rad_s;
  s.has_force = t.force_n.has_value();
  s.force_n = t.force_n.value_or(0.0);
  s.has_force_age = gauge.seen && now >= gauge.last_tick;
  s.force_age_ms = s.has_force_age ? now - gauge.last_tick : 0;
  s.force_failed_readings = gauge.failed_readings;
  s.has_remote = t.remote.has_value();
  s.remote = t.remote.value_or(0.0);
  s.torque_nm = t.torque_nm;
  s.counters = lever.counters();
  s.overruns = lever.timing().stats().overruns;
  s.long_steps = lever.timing().stats().long_steps;
  s.worst_lost_us = lever.timing().stats().worst_lost_us;
  s.worst_interval = lever.timing().stats().worst_interval;
  s.worst_step_ns = lever.timing().stats().worst_step_ns;
  s.encoder_edges = lever.decoder().edges();
  s.encoder_illegal = lever.decoder().illegal_transitions();
  s.encoder_lost = lever.decoder().lost_edges();
  s.passivity = lever.config().passivity.mode;
  s.dissipated_energy_j = t.dissipated_energy_j;
  s.observed_energy_j = t.observed_energy_j;
  return s;
}

nlohmann::json stats_json(const Snapshot& s, const BoardStats& board);

}  // namespace lever::app
