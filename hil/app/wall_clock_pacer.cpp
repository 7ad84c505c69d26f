#include "wall_clock_pacer.hpp"

#include <algorithm>
#include <thread>

namespace lever::hil {

void WallClockPacer::wait() {
  ++grid_tick_;
  const auto due = grid_start_ + std::chrono::milliseconds(grid_tick_);
  const auto now = Clock::now();
  if (now < due) {
    std::this_thread::sleep_until(due);
    return;
  }
  const auto lag = std::chrono::duration_cast<std::chrono::milliseconds>(now - due).count();
  max_lag_ms_ = std::max<std::int64_t>(max_lag_ms_, lag);
  if (lag > kMaxCatchUpMs) {
    ++slips_;
    grid_start_ = whole_ms(now);
    grid_tick_ = 0;
  }
}

}  // namespace lever::hil
