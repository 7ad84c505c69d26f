#pragma once
// Is the loop keeping time? On a board ticks arrive late (scheduling, page faults, a slow bus driver) and steps
// run long; the core must notice, count it, and stop driving the motor once lateness costs the control loops
// more phase than they can spare (moteus latches kTimingViolation, ODrive ERROR_CONTROL_DEADLINE_MISSED).
//
// The budget (docs/firmware.md, "Timing budget", derived in tests/hil/test_loop_margins.cpp): a late tick holds
// the last torque for the time it lost, a long step delays its torque by its duration, and at a crossover f_c
// a delay d costs 360 f_c d degrees. Timing may spend half the phase margin of the TOP at the wall and of the
// HSI in contact: 1.14 ms per crossover period, less a sustained 0.1 ms for the step itself, leaves one lost
// period per 68 ms (the slowest crossover's period). So: lost time (late intervals less one period each, plus
// the whole duration of each step longer than long_step_us) above fault_after - 1 periods within any window of
// `window` ticks latches TIMING; a single interval longer than fault_after is that, at once.
#include <cstdint>

#include "lever/fw/tick.hpp"

namespace lever::fw {

class StepTiming {
 public:
  static constexpr Tick kMaxWindow = 250;  // ticks of lost time kept, one slot each

  struct Config {
    double overrun_periods = 1.5;      // an interval longer than this many periods is an overrun (counted)
    Tick fault_after = 2;              // ticks: a longer interval latches TIMING; fault_after - 1 the budget
    Tick window = 68;                  // ticks over which lost time is summed (1..kMaxWindow)
    std::uint32_t long_step_us = 100;  // a longer step counts its duration as lost time (10 % of a period)
  };
  struct Stats {
    std::uint32_t overruns = 0;       // steps whose interval exceeded overrun_periods
    std::uint32_t long_steps = 0;     // steps that took longer than long_step_ns
    std::uint32_t clock_faults = 0;   // steps whose tick did not advance (a runner bug: a monotonic clock)
    Tick worst_interval = 0;          // ticks
    std::uint64_t worst_step_ns = 0;  // measured by the board's clock; 0 where there is none (HIL)
    std::uint32_t worst_lost_us = 0;  // the most lost time seen within one window
  };

  constexpr StepTiming() noexcept : StepTiming(Config{}) {}
  explicit constexpr StepTiming(const Config& config) noexcept
      : config_(config),
        window_(config.window < 1            ? 1
                : config.window > kMaxWindow ? kMaxWindow
                                             : config.window),
        budget_us_(config.fault_after > 1 ? static_cast<std::uint64_t>(config.fault_after - 1) * kUsPerTick : 0) {}
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
    slide_to(now);
    last_ = now;
    if (interval > stats_.worst_interval) stats_.worst_interval = interval;
    if (static_cast<double>(interval) > config_.overrun_periods) ++stats_.overruns;
    if (interval > 1) lose(static_cast<std::uint64_t>(interval - 1) * kUsPerTick);
    if (interval > config_.fault_after || lost_us_ > budget_us_) late_ = true;
    return interval;
  }

  // How long the step begun last took, by the board's clock. A long one is lost time, judged at the next begin.
  constexpr void step_took(std::uint64_t ns) noexcept {
    if (ns > stats_.worst_step_ns) stats_.worst_step_ns = ns;
    if (ns > std::uint64_t{config_.long_step_us} * 1000u) {
      ++stats_.long_steps;
      lose((ns + 999) / 1000);
    }
  }

  // This step came later than the hard bound, lost time in the window is over budget, or the clock did not
  // advance: the TIMING fault condition.
  constexpr bool violated() const noexcept { return late_; }
  // Lost time within the current window, microseconds.
  constexpr std::uint64_t lost_in_window_us() const noexcept { return lost_us_; }

 private:
  static constexpr std::uint64_t kUsPerTick = 1000;  // kSecondsPerTick, in microseconds

  // Ticks after last_ up to `now` enter the window; what they held leaves it. At most a window's slots.
  constexpr void slide_to(Tick now) noexcept {
    const Tick steps = now - last_ < window_ ? now - last_ : window_;
    for (Tick i = 1; i <= steps; ++i) {
      std::uint32_t& slot = slots_[(last_ + i) % window_];
      lost_us_ -= slot;
      slot = 0;
    }
  }

  constexpr void lose(std::uint64_t us) noexcept {
    std::uint32_t& slot = slots_[last_ % window_];
    const std::uint64_t room = UINT32_MAX - slot;
    const std::uint64_t added = us < room ? us : room;
    slot = static_cast<std::uint32_t>(slot + added);
    lost_us_ += added;
    if (lost_us_ > stats_.worst_lost_us)
      stats_.worst_lost_us = static_cast<std::uint32_t>(lost_us_ > UINT32_MAX ? UINT32_MAX : lost_us_);
  }

  Config config_;
  Tick window_;
  std::uint64_t budget_us_;
  Stats stats_;
  std::uint32_t slots_[kMaxWindow] = {};  // lost time per tick, indexed tick % window
  std::uint64_t lost_us_ = 0;             // their sum
  Tick last_ = 0;
  bool started_ = false;
  bool late_ = false;
};

}  // namespace lever::fw
