#include "lever/app/board_config.hpp"

#include <vector>

#include "lever/board/modbus_gauge_presets.hpp"

namespace lever::app {

const board::ModbusGaugeConfig& default_gauge() {
  static const board::ModbusGaugeConfig gauge = board::preset_gross_weight_int32(board::ModbusTcpEndpoint{});
  return gauge;
}

board::GpioEncoderConfig default_encoder() {
  board::GpioEncoderConfig c;
  c.chip = "gpiochip0";
  c.line_a = board::LineRef::name("ENC_A");
  c.line_b = board::LineRef::name("ENC_B");
  return c;
}

board::PwmMotorConfig default_motor() {
  board::PwmMotorConfig c;
  c.torque_constant_nm_per_a = 0.05;
  c.full_scale_current_a = 20.0;
  return c;
}

board::ModbusGaugeConfig gauge_config(const BoardConfig& b) {
  board::ModbusGaugeConfig c = b.gauge;
  if (b.gauge_link.transport == GaugeLink::Transport::rtu) {
    c.transport = b.gauge_link.rtu;
  } else {
    c.transport = b.gauge_link.tcp;
  }
  // The maximum is no key: a first wait set above it raises it.
  if (c.reconnect_backoff_max < c.reconnect_backoff_initial) c.reconnect_backoff_max = c.reconnect_backoff_initial;
  return c;
}

board::PwmMotorConfig motor_config(const BoardConfig& b) {
  board::PwmMotorConfig c = b.motor;
  const auto& lines = b.motor_lines;
  auto line = [&](const std::optional<board::LineRef>& ref) -> std::optional<board::MotorLineConfig> {
    if (!ref) return std::nullopt;
    return board::MotorLineConfig{lines.chip, *ref, lines.active_low};
  };
  c.enable_line = line(lines.enable);
  c.direction_line = line(lines.direction);
  c.fault_line = line(lines.fault);
  c.positive_torque_only = !c.direction_line;
  return c;
}

board::RealtimeConfig realtime_config(const BoardConfig& b) {
  board::RealtimeConfig c = b.realtime;
  if (!b.realtime_cpus.empty()) c.cpus = board::parse_cpu_list(b.realtime_cpus).value_or(std::vector<unsigned>{});
  return c;
}

}  // namespace lever::app
