#pragma once
// Is the loop keeping time? On a board ticks arrive late (scheduling, page faults, a slow bus driver); the
// core must notice, count it, and stop driving the motor when a step comes so late that its control is no
// longer the one that was designed (moteus latches kTimingViolation, ODrive ERROR_CONTROL_DEADLINE_MISSED).
#include <cstdint>

#include "lever/fw/tick.hpp"

namespace lever::fw {

class StepTiming {
 public:
  struct Config {
    double overrun_periods = 1.5;  // an interval longer than this many periods is an overrun (counted)
    Tick fault_after = 5;          // an interval longer than this many ticks (5 ms) latches TIMING
  };
  struct Stats {
    std::uint32_t overruns = 0;       // steps whose interval exceeded overrun_periods
    std::uint32_t clock_faults = 0;   // steps whose tick did not advance (a runner bug: a monotonic clock)
    Tick worst_interval = 0;          // ticks
    std::uint64_t worst_step_ns = 0;  // measured by the board's clock; 0 where there is none (HIL)
  };

  constexpr StepTiming() noexcept : StepTiming(Config{}) {}
  explicit constexpr StepTiming(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const Stats& stats() const noexcept { return stats_; }

  // A step begins at `now`. Returns the interval since the last step in ticks: 0 for the first step and for
  // a tick that did not advance (nothing to integrate over).
  constexpr Tick begin(Tick now) noexcept {
    late_ = false;
    if (!started_) {
      started_ = true;
      last_ = now;
      return 0;
    }
    if (now <= last_) {
      ++stats_.clock_faults;
      late_ = true;
      return 0;
    }
    const Tick interval = now - last_;
    last_ = now;
    if (interval > stats_.worst_interval) stats_.worst_interval = interval;
    if (static_cast<double>(interval) > config_.overrun_periods) ++stats_.overruns;
    if (interval > config_.fault_after) late_ = true;
    return interval;
  }

  constexpr void step_took(std::uint64_t ns) noexcept {
    if (ns > stats_.worst_step_ns) stats_.worst_step_ns = ns;
  }

  // This step came later than the hard bound, or the clock did not advance: the TIMING fault condition.
  constexpr bool violated() const noexcept { return late_; }

 private:
  Config config_;
  Stats stats_;
  Tick last_ = 0;
  bool started_ = false;
  bool late_ = false;
};

}  // namespace lever::fw
