#pragma once
// The firmware's clock: one tick per 1 ms sample period, counted from power-up.
#include <cstdint>

namespace lever::fw {

using Tick = std::uint64_t;

inline constexpr double kSecondsPerTick = 1e-3;

}  // namespace lever::fw
