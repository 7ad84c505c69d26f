#pragma once
// Everything lever-fw is configured with: the firmware core's LeverConfig and the board's backends, as one
// TOML file whose keys carry their units (docs/lever-fw.md lists them with defaults).
#include <string>

#include "lever/app/config_schema.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/linux/gpio_encoder_config.hpp"

namespace lever::app {

struct BoardConfig {
  std::string can_interface = "can0";
  // The encoder's lines, by name or by offset on the chip ("ENC_A", "17"); an empty index line: none.
  std::string encoder_chip = "gpiochip0";
  std::string encoder_line_a = "ENC_A", encoder_line_b = "ENC_B", encoder_line_z;
  bool encoder_active_low = false;
  std::int64_t encoder_edge_latency_us = 50;
};

// The libgpiod backend's configuration from the board's keys.
linux_io::GpioEncoderConfig encoder_config(const BoardConfig& board);

struct FwConfig {
  fw::LeverConfig lever{};
  BoardConfig board{};
};

// The schema of a FwConfig: every key, bound to `config`'s fields.
ConfigSchema schema_for(FwConfig& config);

// Loads `path` over the defaults. On failure: the message naming file, key and problem.
struct LoadedConfig {
  FwConfig config;
  std::string error;  // empty on success
};
LoadedConfig load_fw_config(const std::string& path);

}  // namespace lever::app
