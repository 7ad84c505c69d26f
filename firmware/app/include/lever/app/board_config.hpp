#pragma once
// The [board] part of lever-fw's configuration: each backend's own configuration struct, its keys bound to its
// fields (board_keys.hpp). Where a file says more than a backend's struct keeps (both Modbus endpoints, one chip
// for lines that may all be absent, a CPU list as written), that part is kept as the file says it, beside the
// struct, and the backend's configuration is made of both by its accessor below.
#include <optional>
#include <string>

#include "lever/board/board_can_port_config.hpp"
#include "lever/board/gpio_encoder_config.hpp"
#include "lever/board/line_ref.hpp"
#include "lever/board/loop_watchdog.hpp"
#include "lever/board/modbus_gauge_config.hpp"
#include "lever/board/pwm_motor_config.hpp"
#include "lever/board/realtime_config.hpp"

namespace lever::app {

// The board's default amplifier: the common weighing-amplifier layout (board::preset_gross_weight_int32:
// the gross weight as a 32-bit integer in holding registers 0-1, high word first, in grams) on Modbus TCP,
// with the board layer's default timing and the testbed load cell's range as its saturation bounds.
const board::ModbusGaugeConfig& default_gauge();
// The encoder on gpiochip0's lines ENC_A and ENC_B, no index line.
board::GpioEncoderConfig default_encoder();
// The testbed's motor and driver on pwmchip0's channel 0 (its lines: MotorLines').
board::PwmMotorConfig default_motor();

// The amplifier's Modbus link as [board.gauge] gives it: the keys of both endpoints are read and checked whichever
// the transport, and a board::ModbusTransport holds the chosen one alone.
struct GaugeLink {
  enum class Transport { tcp, rtu };
  Transport transport = Transport::tcp;
  board::ModbusTcpEndpoint tcp;
  board::ModbusRtuEndpoint rtu;
};

// The motor driver's lines as [board.motor] names them: one chip and one polarity for the three, each line
// optional (""). PwmMotorConfig keeps a chip per line and nothing for a line left out, so it could not keep the
// chip of lines that are all left out.
struct MotorLines {
  std::string chip = "gpiochip0";
  std::optional<board::LineRef> enable = board::LineRef::name("MOTOR_EN");
  std::optional<board::LineRef> direction = board::LineRef::name("MOTOR_DIR");
  std::optional<board::LineRef> fault = board::LineRef::name("MOTOR_FAULT");
  bool active_low = false;
};

struct BoardConfig {
  board::BoardCanPortConfig can;  // its pair: lever.pair (can_config in fw_config.hpp)
  board::GpioEncoderConfig encoder = default_encoder();
  // The strain gauge's weighing amplifier over Modbus. It reports newtons (raw * scale + offset), so with it
  // the core's gauge.newton_per_unit stays 1.
  board::ModbusGaugeConfig gauge = default_gauge();  // its transport: gauge_link (gauge_config)
  GaugeLink gauge_link;
  board::PwmMotorConfig motor = default_motor();  // its lines: motor_lines (motor_config)
  MotorLines motor_lines;
  board::RealtimeConfig realtime;  // its cpus: realtime_cpus (realtime_config)
  // The loop's CPUs as written ("2", "0,2-3"; empty: any), and so printed back; a text that is no CPU list is a
  // problem of the configuration as a whole (load_fw_config), said after those of single keys.
  std::string realtime_cpus;
  // A hardware watchdog fed only while the loop advances (board::LoopWatchdog); device empty: none. The service
  // manager's watchdog needs no key: its interval is the unit's WatchdogSec= (lever-fw@.service).
  board::LoopWatchdogConfig watchdog;
};

// The backends' configurations whose keys are not all theirs: the gauge with the endpoint the transport names
// (and a backoff maximum no shorter than the first wait), the motor with its lines, the loop with its CPUs (none
// for a text that is no CPU list, which load_fw_config refuses).
board::ModbusGaugeConfig gauge_config(const BoardConfig& board);
board::PwmMotorConfig motor_config(const BoardConfig& board);
board::RealtimeConfig realtime_config(const BoardConfig& board);

}  // namespace lever::app
