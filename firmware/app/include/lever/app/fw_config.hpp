#pragma once
// Everything lever-fw is configured with: the firmware core's LeverConfig and the board's backends, as one
// TOML file whose keys carry their units (docs/lever-fw.md lists them with defaults).
#include <optional>
#include <string>
#include <vector>

#include "lever/board/board_can_port_config.hpp"
#include "lever/board/gpio_encoder_config.hpp"
#include "lever/board/loop_watchdog.hpp"
#include "lever/board/modbus_gauge_config.hpp"
#include "lever/board/modbus_gauge_presets.hpp"
#include "lever/board/pwm_motor_config.hpp"
#include "lever/board/realtime_config.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/program/config_schema.hpp"

namespace lever::app {

// The board's default amplifier: the common weighing-amplifier layout (board::preset_gross_weight_int32:
// the gross weight as a 32-bit integer in holding registers 0-1, high word first, in grams) on Modbus TCP,
// with the board layer's default timing and the testbed load cell's range as its saturation bounds.
const board::ModbusGaugeConfig& default_gauge();

struct BoardConfig {
  std::string can_interface = "can0";
  // The encoder's lines, by name or by offset on the chip ("ENC_A", "17"); an empty index line: none.
  std::string encoder_chip = "gpiochip0";
  std::string encoder_line_a = "ENC_A", encoder_line_b = "ENC_B", encoder_line_z;
  bool encoder_active_low = false;
  std::int64_t encoder_edge_latency_us = 50;

  // The strain gauge's weighing amplifier over Modbus. It reports newtons (raw * scale + offset), so with it
  // the core's gauge.newton_per_unit stays 1.
  std::string gauge_transport = "tcp";  // tcp or rtu
  std::string gauge_host = "127.0.0.1";
  std::int64_t gauge_port = 502, gauge_unit_id = 255;
  std::string gauge_device = "/dev/ttyUSB0";
  std::int64_t gauge_baud = 115200, gauge_stop_bits = 1, gauge_slave_id = 1;
  board::Parity gauge_parity = board::Parity::none;
  // Defaults: default_gauge()'s.
  board::GaugeRegisterMap gauge_registers = default_gauge().registers;
  double gauge_saturation_raw_min = *default_gauge().registers.saturation_raw_min;
  double gauge_saturation_raw_max = *default_gauge().registers.saturation_raw_max;
  std::int64_t gauge_poll_us = default_gauge().poll_period.count();
  std::int64_t gauge_timeout_us = default_gauge().response_timeout.count();
  std::int64_t gauge_reconnect_backoff_ms = default_gauge().reconnect_backoff_initial.count();

  // The motor: a sysfs PWM channel and optional enable, direction and fault lines ("" : none).
  std::string motor_sysfs_root = "/sys";
  std::int64_t motor_pwm_chip = 0, motor_pwm_channel = 0, motor_period_ns = 50000;
  bool motor_pwm_inversed = false;
  double motor_torque_constant_nm_per_a = 0.05, motor_gear_ratio = 1.0, motor_full_scale_current_a = 20.0;
  double motor_max_duty = 0.95, motor_deadband_nm = 0.0;
  std::string motor_line_chip = "gpiochip0";
  std::string motor_enable_line = "MOTOR_EN", motor_direction_line = "MOTOR_DIR", motor_fault_line = "MOTOR_FAULT";
  bool motor_lines_active_low = false;

  // The real-time loop.
  std::int64_t realtime_priority = 80;
  std::string realtime_cpus;  // "2", "0,2-3"; empty: any
  bool realtime_lock_memory = true;
  std::int64_t realtime_prefault_stack_kib = 256;

  std::int64_t can_link_retry_ms = 50, can_link_retry_max_ms = 1000;

  // A hardware watchdog fed only while the loop advances (board::LoopWatchdog); empty: none. The service
  // manager's watchdog needs no key: its interval is the unit's WatchdogSec= (lever-fw@.service).
  std::string watchdog_device;
  std::int64_t watchdog_timeout_s = 2;
};

// The libgpiod backend's configuration from the board's keys.
board::GpioEncoderConfig encoder_config(const BoardConfig& board);
// The Modbus backend's configuration from the board's keys.
board::ModbusGaugeConfig gauge_config(const BoardConfig& board);
board::PwmMotorConfig motor_config(const BoardConfig& board);
board::RealtimeConfig realtime_config(const BoardConfig& board);
board::LoopWatchdogConfig watchdog_config(const BoardConfig& board);

// The core's defaults, but for a board: the Modbus gauge already reports newtons (its register map scales
// the amplifier's units), so the core's own gauge calibration is the identity, its saturation the load cell's
// capacity in newtons, and its staleness window the default gauge's longest gap for one missed poll, plus a
// tick.
fw::LeverConfig board_lever_defaults();

struct FwConfig {
  fw::LeverConfig lever = board_lever_defaults();
  BoardConfig board{};
};

board::BoardCanPortConfig can_config(const FwConfig& config);

// The schema of a FwConfig: every key, bound to `config`'s fields.
program::ConfigSchema schema_for(FwConfig& config);

// The command line's overrides: applied over the file before anything is validated, each through the same
// check as its key in the file, so that an override cannot pass what the file could not.
struct ConfigOverrides {
  std::optional<protocol::Role> role;  // --role: lever.role
  std::optional<std::string> can;      // --can: board.can.interface
  // --set KEY=VALUE, in order, after the file and before --role and --can: VALUE is a TOML value ("vcan0" quoted,
  // 0.05, true), checked as the key is in a file.
  std::vector<std::string> sets;
};

// Loads `path` over the defaults, then the overrides. On failure: the message naming file, key and problem
// (or the option, for a problem an override brought).
struct LoadedConfig {
  FwConfig config;
  std::string error;  // empty on success
};
LoadedConfig load_fw_config(const std::string& path, const ConfigOverrides& overrides = {});

// The motor's keys alone ([board.motor]), read from a file whatever else in it is wrong: what --motor-off needs.
// `motor` is empty when they cannot be had (the file unreadable or not TOML, a motor key wrong or missing, the
// motor's configuration invalid); `problems` lists every problem the file has, the motor's keys' first.
struct MotorKeys {
  std::optional<board::PwmMotorConfig> motor;
  std::vector<std::string> problems;
};
// Which keys must be in the file, since a key left out would be its default: `identity`, those that say which
// hardware the motor is (the PWM chip and channel, the three lines, and the lines' chip when one is named);
// `every_key`, all of [board.motor] (the motor state, which has them all when written whole).
enum class MotorKeysRequired { identity, every_key };
MotorKeys motor_keys_from(const toml::table& table, const std::string& source, MotorKeysRequired required);
// A configuration's motor keys (`identity` required). Its other problems, those of one key and those of keys
// together (load_fw_config's), are listed too.
MotorKeys load_motor_keys(const std::string& path);

// The [board.motor] keys of a configuration as a TOML file of their own, which load_motor_keys reads back: the
// motor state lever-fw writes at start (--motor-state) for a --motor-off that cannot read the configuration.
std::string motor_keys_toml(FwConfig config);

}  // namespace lever::app
