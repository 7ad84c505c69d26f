#pragma once
// Register maps of two common weighing-amplifier layouts, with the gauge's default timing; docs/modbus-gauge.md
// says where they come from and what to check in a device's manual.
#include "lever/platform/modbus_gauge_config.hpp"

namespace lever::platform {

// Gross weight as a signed 32-bit count in holding registers 0 and 1 (a manual's 40001-40002), high word
// first. The count is in the amplifier's display units; newtons_per_count converts (the default is for an
// amplifier calibrated to show grams: 1 g = 9.80665 mN).
ModbusGaugeConfig preset_gross_weight_int32(ModbusTransport transport, double newtons_per_count = 9.80665e-3);

// The force as an IEEE 754 float32 in input registers 0 and 1 (a manual's 30001-30002), high word first, in
// the unit the amplifier was calibrated in; newtons_per_unit converts (1 for an amplifier calibrated in N).
ModbusGaugeConfig preset_force_float32(ModbusTransport transport, double newtons_per_unit = 1.0);

}  // namespace lever::platform
