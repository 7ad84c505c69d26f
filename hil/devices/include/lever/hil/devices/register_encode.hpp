#pragma once
// A force as the registers a weighing amplifier would hold for it: the inverse of the board layer's
// decode_registers (modbus_register_decode.hpp) and of its newtons = raw * scale + offset. Pure, so every type
// and word order is checked against the decoder without a server.
#include <array>
#include <cstdint>

#include "lever/board/modbus_gauge_config.hpp"

namespace lever::hil::devices {

struct RegisterWords {
  std::array<std::uint16_t, 2> words{};  // lowest address first
  int count = 0;                         // register_count(type): 1 or 2
};

// raw = (newtons - offset) / scale. No rounding or clamping here: encode_registers() does that per type.
double raw_for_newtons(double newtons, const board::GaugeRegisterMap& map) noexcept;

// `raw` in the registers of `type`. Integer types round to nearest and clamp to the type's range (an
// amplifier's count stops at its end; it does not wrap), a NaN becomes 0 (an integer register cannot say "not
// a number"; a failure test mutes the server instead). float32 rounds to the nearest float, clamps finite
// values beyond its range to the largest float, and passes NaN and infinity through: amplifiers send those to
// signal overload, and the gauge must count them as invalid readings.
RegisterWords encode_registers(double raw, board::RegisterType type, board::WordOrder order) noexcept;

}  // namespace lever::hil::devices
