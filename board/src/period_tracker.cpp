#include "lever/board/period_tracker.hpp"

namespace lever::board {

PeriodTracker::PeriodTracker(std::int64_t start_ns, std::int64_t period_ns) noexcept
    : start_ns_(start_ns), period_ns_(period_ns) {}

std::int64_t PeriodTracker::deadline_ns() const noexcept {
  return start_ns_ + static_cast<std::int64_t>(next_) * period_ns_;
}

fw::Tick PeriodTracker::woke(std::int64_t now_ns, LoopStats& stats) noexcept {
  const std::int64_t late_ns = now_ns - deadline_ns();
  stats.wake_latency.record_ns(late_ns);
  if (late_ns >= period_ns_) {
    const auto whole = static_cast<fw::Tick>(late_ns / period_ns_);
    ++stats.late_wakes;
    stats.skipped_periods += whole;
    next_ += whole;
  }
  woke_ns_ = now_ns;
  return next_;
}

void PeriodTracker::step_done(std::int64_t now_ns, LoopStats& stats) noexcept {
  const std::int64_t took_ns = now_ns - woke_ns_;
  ++stats.steps;
  stats.step_duration.record_ns(took_ns);
  if (took_ns > period_ns_) ++stats.long_steps;
  if (took_ns > stats.worst_step_ns) stats.worst_step_ns = took_ns;
  ++next_;
}

}  // namespace lever::board
