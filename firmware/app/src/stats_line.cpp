#include "lever/app/stats_line.hpp"

#include "lever/protocol/fault_names.hpp"

namespace lever::app {

nlohmann::json stats_json(const Snapshot& s, const BoardStats& board) {
  auto optional = [](const auto& v) { return v ? nlohmann::json(*v) : nlohmann::json(); };
  auto if_set = [](bool set, const auto& v) { return set ? nlohmann::json(v) : nlohmann::json(); };
  return {
      {"role", s.role == protocol::Role::hsi ? "hsi" : "top"},
      {"pair", s.pair},
      {"state", std::string(protocol::name(s.state))},
      {"faults", protocol::fault_name_list(s.faults)},
      {"position_rad", s.position_rad},
      {"position_valid", s.position_valid},
      {"velocity_rad_s", s.velocity_rad_s},
      {"force_n", if_set(s.has_force, s.force_n)},
      {"force_age_ms", if_set(s.has_force_age, s.force_age_ms)},
      {"force_failed_readings", s.force_failed_readings},
      {"remote", if_set(s.has_remote, s.remote)},
      {"torque_nm", s.torque_nm},
      {"tx_frames", s.counters.tx_frames},
      {"rx_frames", s.counters.rx_frames},
      {"data_sent", s.counters.data_sent},
      {"refresh_sent", s.counters.refresh_sent},
      {"overruns", s.overruns},
      {"worst_step_interval_ms", s.worst_interval},
      {"worst_step_us", static_cast<double>(s.worst_step_ns) * 1e-3},
      {"long_steps", s.long_steps},
      {"worst_lost_in_window_us", s.worst_lost_us},
      {"wakeup_latency_us",
       {{"p50", optional(board.wakeup_p50_us)},
        {"p99", optional(board.wakeup_p99_us)},
        {"max", optional(board.wakeup_max_us)}}},
      {"step_us",
       {{"p50", optional(board.step_p50_us)},
        {"p99", optional(board.step_p99_us)},
        {"max", optional(board.step_max_us)}}},
      {"encoder", {{"edges", s.encoder_edges}, {"illegal", s.encoder_illegal}, {"lost", s.encoder_lost}}},
      {"modbus",
       {{"polls", optional(board.modbus_polls)},
        {"errors", optional(board.modbus_errors)},
        {"timeouts", optional(board.modbus_timeouts)},
        {"crc_errors", optional(board.modbus_crc_errors)},
        {"exceptions", optional(board.modbus_exceptions)},
        {"reconnects", optional(board.modbus_reconnects)}}},
      {"minor_faults", optional(board.minor_faults)},
      {"passivity",
       {{"mode", fw::name(s.passivity)},
        {"energy_sent", s.counters.energy_sent},
        {"dissipated_energy_j", s.dissipated_energy_j},
        {"observed_energy_j", s.observed_energy_j}}},
  };
}

}  // namespace lever::app
