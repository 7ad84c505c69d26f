#pragma once
// Everything lever-fw is configured with: the firmware core's LeverConfig and the board's backends, as one
// TOML file whose keys carry their units (docs/lever-fw.md lists them with defaults).
#include <optional>
#include <string>
#include <vector>

#include "lever/app/board_config.hpp"
#include "lever/board/board_can_port_config.hpp"
#include "lever/board/pwm_motor_config.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/program/config_schema.hpp"

namespace lever::app {

// The core's defaults, but for a board: the Modbus gauge already reports newtons (its register map scales
// the amplifier's units), so the core's own gauge calibration is the identity, its saturation the load cell's
// capacity in newtons, and its staleness window the default gauge's longest gap for one missed poll, plus a
// tick.
fw::LeverConfig board_lever_defaults();

struct FwConfig {
  fw::LeverConfig lever = board_lever_defaults();
  BoardConfig board{};
};

// The CAN port's configuration: the board's, for the lever's pair.
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
