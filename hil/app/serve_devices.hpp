#pragma once
// One lever's devices as lever-hil serve plays them, where its lever-fw configuration says they are: the encoder's
// lines, the motor read back from its PWM tree, and the strain gauge as a Modbus server (for a lever that reads one).
#include <cmath>
#include <cstdint>
#include <optional>

#include "lever/app/fw_config.hpp"
#include "lever/hil/devices/encoder_lines.hpp"
#include "lever/hil/devices/gauge_server.hpp"
#include "lever/hil/devices/motor_readback.hpp"

namespace lever::hil {

struct LeverDevices {
  std::optional<devices::EncoderLines> encoder;
  std::optional<devices::MotorReadback> motor;
  std::optional<devices::GaugeServer> gauge;             // only a lever that reads its gauge has one (while it is up)
  std::optional<board::ModbusGaugeConfig> gauge_config;  // where it serves, to start it again
  std::uint64_t stopped_gauges_requests = 0;             // requests the gauges stopped since had served
  double counts_per_radian = 0.0;
  std::int64_t count_origin = 0;  // the count at power-up: an incremental encoder's count starts anywhere

  std::int64_t count_at(double angle) const {
    return static_cast<std::int64_t>(std::floor(angle * counts_per_radian)) - count_origin;
  }
  // The amplifier dies (its listener and connection close, its pty goes) and comes back; fault injection.
  void stop_gauge();
  bool start_gauge();  // false when it cannot serve again (said on stderr)
  std::uint64_t gauge_requests() const { return stopped_gauges_requests + (gauge ? gauge->counters().requests : 0); }
};

// Opens them for a lever powered up at `angle`; on failure says which device and why on stderr, and returns none.
std::optional<LeverDevices> open_devices(const app::FwConfig& config, double angle, double max_edge_rate_hz);

}  // namespace lever::hil
