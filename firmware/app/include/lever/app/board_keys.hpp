#pragma once
// The [board] keys: each part of the board binds its own keys to its own configuration's fields, so that a key
// is declared once, with its range, unit and documentation, beside the field it sets (docs/lever-fw.md lists them).
#include <string>

#include "lever/app/board_config.hpp"
#include "lever/program/config_schema.hpp"

namespace lever::app {

void bind_can(program::ConfigSchema& s, board::BoardCanPortConfig& can);
void bind_encoder(program::ConfigSchema& s, board::GpioEncoderConfig& encoder);
void bind_gauge(program::ConfigSchema& s, board::ModbusGaugeConfig& gauge, GaugeLink& link);
void bind_motor(program::ConfigSchema& s, board::PwmMotorConfig& motor, MotorLines& lines);
void bind_realtime(program::ConfigSchema& s, board::RealtimeConfig& realtime, std::string& cpus);
void bind_watchdog(program::ConfigSchema& s, board::LoopWatchdogConfig& watchdog);

// Every [board] key, in the order --check-config prints them.
void bind_board(program::ConfigSchema& s, BoardConfig& board);

}  // namespace lever::app
