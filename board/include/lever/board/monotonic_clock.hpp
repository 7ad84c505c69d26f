#pragma once
// CLOCK_MONOTONIC in nanoseconds: the one clock of the board's loop, its backends' time stamps and deadlines, and
// the clock the kernel stamps GPIO edge events with since Linux 5.7, so that all of them can be compared.
#include <cstdint>

namespace lever::board {

std::int64_t monotonic_ns() noexcept;

}  // namespace lever::board
