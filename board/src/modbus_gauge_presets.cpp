#include "lever/board/modbus_gauge_presets.hpp"

#include <cmath>
#include <utility>

namespace lever::board {

ModbusGaugeConfig preset_gross_weight_int32(ModbusTransport transport, double newtons_per_count, double capacity_n) {
  ModbusGaugeConfig config;
  config.transport = std::move(transport);
  const double counts = std::trunc(std::fabs(capacity_n / newtons_per_count));
  config.registers = GaugeRegisterMap{
      .function = RegisterFunction::holding,
      .address = 0,
      .type = RegisterType::int32,
      .word_order = WordOrder::high_first,
      .scale = newtons_per_count,
      .saturation_raw_min = -counts,
      .saturation_raw_max = counts,
  };
  return config;
}

ModbusGaugeConfig preset_force_float32(ModbusTransport transport, double newtons_per_unit, double capacity_n) {
  ModbusGaugeConfig config;
  config.transport = std::move(transport);
  const double units = std::fabs(capacity_n / newtons_per_unit);
  config.registers = GaugeRegisterMap{
      .function = RegisterFunction::input,
      .address = 0,
      .type = RegisterType::float32,
      .word_order = WordOrder::high_first,
      .scale = newtons_per_unit,
      .saturation_raw_min = -units,
      .saturation_raw_max = units,
  };
  return config;
}

}  // namespace lever::board
