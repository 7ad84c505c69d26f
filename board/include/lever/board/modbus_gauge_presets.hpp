#pragma once
// Register maps of two common weighing-amplifier layouts, with the gauge's default timing and the saturation
// bounds of the amplifier's range; docs/modbus-gauge.md says where they come from and what to check in a
// device's manual.
#include "lever/board/modbus_gauge_config.hpp"

namespace lever::board {

// The testbed's load cell: 50 N rated capacity at 2 mV/V, read by a Flintec DAD 141.1 whose maximum output
// (CM, CI) is set to the cell's capacity (docs/hil-model.md, "The strain-gauge amplifier"). Beyond it the
// amplifier reads at its limit, so a reading at the capacity is a saturated one.
inline constexpr double kTestbedLoadCellCapacityN = 50.0;

// Gross weight as a signed 32-bit count in holding registers 0 and 1 (a manual's 40001-40002), high word
// first. The count is in the amplifier's display units; newtons_per_count converts (the default is for an
// amplifier calibrated to show grams: 1 g = 9.80665 mN). Saturated at +-capacity_n in counts, rounded toward
// zero to whole counts (50 N in grams: +-5098).
ModbusGaugeConfig preset_gross_weight_int32(ModbusTransport transport, double newtons_per_count = 9.80665e-3,
                                            double capacity_n = kTestbedLoadCellCapacityN);

// The force as an IEEE 754 float32 in input registers 0 and 1 (a manual's 30001-30002), high word first, in
// the unit the amplifier was calibrated in; newtons_per_unit converts (1 for an amplifier calibrated in N).
// Saturated at +-capacity_n in that unit.
ModbusGaugeConfig preset_force_float32(ModbusTransport transport, double newtons_per_unit = 1.0,
                                       double capacity_n = kTestbedLoadCellCapacityN);

}  // namespace lever::board
