#pragma once
// The monitor and the reader's state behind one lock: the readers feed it frame by frame (a batch per lock),
// the screen copies a snapshot out of it ten times a second, so drawing never holds up reading.
#include <cstdint>
#include <mutex>

#include "pair_monitor.hpp"
#include "screen_text.hpp"

namespace lever::view {

struct LiveMonitor {
  explicit LiveMonitor(MonitorConfig config) : monitor(config) {}
  std::mutex mutex;
  PairMonitor monitor;
  ReaderState reader;
};

// Microseconds of CLOCK_REALTIME: the clock of the kernel's receive time stamps (SO_TIMESTAMP).
std::int64_t realtime_us() noexcept;

}  // namespace lever::view
