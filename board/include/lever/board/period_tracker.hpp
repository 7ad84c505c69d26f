#pragma once
// The real-time loop's bookkeeping, apart from any clock so that it is tested with made-up times: which
// period each wake-up serves, how late it came, what was skipped, and which steps ran long.
//
// Tick k is due at start + k * period (the first at k = 1). A wake-up late by a whole period or more serves the
// latest tick already due and skips the ones before it, so the core sees the gap as an interval of several
// ticks (an overrun, and past its bound a TIMING fault) instead of a burst of catch-up steps.
#include <cstdint>
#include <optional>

#include "lever/board/latency_histogram.hpp"
#include "lever/fw/tick.hpp"

namespace lever::board {

struct LoopStats {
  LatencyHistogram wake_latency;   // actual wake-up minus the time its tick was due
  LatencyHistogram step_duration;  // wake-up to the step's end: the CPU a step takes, preemption included
  std::uint64_t steps = 0;
  std::uint64_t late_wakes = 0;       // wake-ups a whole period or more after their tick was due
  std::uint64_t skipped_periods = 0;  // ticks never served because of them
  std::uint64_t long_steps = 0;       // steps that took longer than a period
  std::int64_t worst_step_ns = 0;
  // getrusage over the steady part (RealtimeConfig::steady_after_ticks to the end); empty if the run ended
  // before it began.
  std::optional<long> minor_faults_steady;
  std::optional<long> major_faults_steady;

  // Late wake-ups and long steps; one event may be both (a long step makes the next wake-up late).
  std::uint64_t overruns() const noexcept { return late_wakes + long_steps; }
};

class PeriodTracker {
 public:
  PeriodTracker(std::int64_t start_ns, std::int64_t period_ns) noexcept;

  // When the tick to serve next is due: the time to sleep until.
  std::int64_t deadline_ns() const noexcept;
  // The thread woke at `now_ns` for deadline_ns(): records the latency, skips the ticks it missed whole, and
  // returns the tick to serve.
  fw::Tick woke(std::int64_t now_ns, LoopStats& stats) noexcept;
  // The step for that tick ended at `now_ns`.
  void step_done(std::int64_t now_ns, LoopStats& stats) noexcept;

 private:
  std::int64_t start_ns_;
  std::int64_t period_ns_;
  fw::Tick next_ = 1;
  std::int64_t woke_ns_ = 0;
};

}  // namespace lever::board
