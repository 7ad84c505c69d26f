#pragma once
// What a lever shows of itself every tick (logs, the stats line, the HIL) and what it counts.
#include <cstdint>
#include <optional>

#include "lever/fw/send_cause.hpp"

namespace lever::fw {

struct LeverCounters {
  std::uint32_t rx_frames = 0;    // frames for this pair, decoded
  std::uint32_t rx_rejected = 0;  // frames for this pair that failed to decode
  std::uint32_t rx_stale = 0;     // duplicate or reordered data frames, not used
  std::uint32_t tx_frames = 0;
  std::uint32_t tx_dropped = 0;         // the CAN queue was full
  std::uint32_t data_sent = 0;          // data frames sent, refreshes included
  std::uint32_t refresh_sent = 0;       // of which sent by the refresh period, a restart or a reconfiguration
  std::uint32_t energy_sent = 0;        // energy frames (passivity observe or tdpa)
  std::uint32_t settings_sent = 0;      // settings frames, on change and periodic
  std::uint32_t commands_rejected = 0;  // commands refused by the supervisor or with invalid parameters
};

struct LeverTelemetry {
  double position_rad = 0.0;  // lever coordinates; meaningful only while position_valid
  bool position_valid = false;
  double velocity_rad_s = 0.0;             // the tracking estimate: smooth, for damping and control
  double velocity_difference_rad_s = 0.0;  // the quantized position's backward difference: exactly 0 at rest
  double velocity_window_rad_s = 0.0;      // its adaptive-window difference (0 unless the HSI sends it)
  std::optional<double> force_n;           // own strain gauge, calibrated; empty when stale
  // Reconstructed peer value: HSI velocity at the TOP, force at the HSI (after the passivity controller's scale).
  std::optional<double> remote;
  double position_ref_rad = 0.0;  // TOP tracking reference
  double velocity_ref_rad_s = 0.0;
  double torque_demand_nm = 0.0;  // before the limit
  double torque_nm = 0.0;         // commanded
  bool motor_enabled = false;
  bool sent_data = false;                      // this tick (deadband or refresh)
  bool sent_refresh = false;                   // this tick, and it was a refresh
  SendCause sent_cause = SendCause::deadband;  // this tick's data frame's (data_channel.hpp)
  // Passivity (zero while off), since this lever armed: what the controller dissipated, and the observer's
  // energy (the peer's input as received less this port's output).
  double dissipated_energy_j = 0.0;
  double observed_energy_j = 0.0;
};

}  // namespace lever::fw
