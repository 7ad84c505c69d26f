#include "lever/platform/modbus_gauge_presets.hpp"

#include <utility>

namespace lever::platform {

ModbusGaugeConfig preset_gross_weight_int32(ModbusTransport transport, double newtons_per_count) {
  ModbusGaugeConfig config;
  config.transport = std::move(transport);
  config.registers = GaugeRegisterMap{
      .function = RegisterFunction::holding,
      .address = 0,
      .type = RegisterType::int32,
      .word_order = WordOrder::high_first,
      .scale = newtons_per_count,
  };
  return config;
}

ModbusGaugeConfig preset_force_float32(ModbusTransport transport, double newtons_per_unit) {
  ModbusGaugeConfig config;
  config.transport = std::move(transport);
  config.registers = GaugeRegisterMap{
      .function = RegisterFunction::input,
      .address = 0,
      .type = RegisterType::float32,
      .word_order = WordOrder::high_first,
      .scale = newtons_per_unit,
  };
  return config;
}

}  // namespace lever::platform
