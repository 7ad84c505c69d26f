#pragma once
// The board's 1 kHz loop: a thread made real-time (SCHED_FIFO, CPU affinity, locked memory, a pre-faulted
// stack) that wakes at each period boundary with clock_nanosleep(TIMER_ABSTIME) on CLOCK_MONOTONIC, hands the
// step the tick it serves, and keeps wake-up latency and overrun statistics (period_tracker.hpp).
//
// Without the privileges (CAP_SYS_NICE or RLIMIT_RTPRIO; CAP_IPC_LOCK or RLIMIT_MEMLOCK) it does not fail: it
// runs best-effort and says so once, in warning(), for the caller to log.
#include <sched.h>
#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <stop_token>
#include <string>
#include <vector>

#include "lever/board/monotonic_clock.hpp"
#include "lever/board/period_tracker.hpp"
#include "lever/board/realtime_config.hpp"
#include "lever/board/result.hpp"
#include "lever/fw/tick.hpp"

namespace lever::board {

// What open() obtained of what the config asked.
struct RealtimeGrants {
  int fifo_priority = 0;  // 0: SCHED_OTHER; may be below the one asked (RLIMIT_RTPRIO)
  bool memory_locked = false;
  std::size_t stack_prefaulted_bytes = 0;
  std::vector<unsigned> cpus;  // as set; empty: not set
};

class RealtimeLoop {
 public:
  // Applies the config to the calling thread, which must be the one that calls run(): scheduling with
  // SCHED_RESET_ON_FORK (children start as ordinary processes), affinity, mlockall, the stack. Fails only on a
  // config that cannot be meant (validate(), CPUs that are not there); a privilege refused is a warning.
  static Result<RealtimeLoop> open(const RealtimeConfig& config);

  // Move-constructible only (what Result needs); a moved-from loop restores nothing and may only be
  // destroyed. The destructor gives the thread back its scheduling and CPUs as they were, and unlocks memory if
  // open() locked it.
  RealtimeLoop(RealtimeLoop&&) noexcept;
  RealtimeLoop& operator=(RealtimeLoop&&) = delete;
  RealtimeLoop(const RealtimeLoop&) = delete;
  RealtimeLoop& operator=(const RealtimeLoop&) = delete;
  ~RealtimeLoop();

  // Calls step(fw::Tick) once per period until `stop` is requested (checked before each sleep), tick 1 at the
  // first whole multiple of the period on CLOCK_MONOTONIC after the call. Per period the loop allocates nothing and
  // calls clock_nanosleep and twice clock_gettime (the vDSO's where the clocksource allows); getrusage once when the
  // steady part starts and once at the end. Statistics start afresh with each run. Returns false, running nothing, on a
  // thread other than open()'s.
  template <typename Step>
  bool run(Step&& step, std::stop_token stop) {
    if (!begin_run()) return false;
    while (!stop.stop_requested()) {
      sleep_until(tracker_.deadline_ns());
      const fw::Tick tick = tracker_.woke(monotonic_ns(), *stats_);
      if (!steady_ && tick >= steady_after_) mark_steady();
      step(tick);
      tracker_.step_done(monotonic_ns(), *stats_);
    }
    end_run();
    return true;
  }

  // Empty when everything asked for was granted; else one message for the log, saying what was refused,
  // why, and what the loop does instead.
  const std::string& warning() const noexcept { return warning_; }
  // Everything asked for was granted.
  bool privileged() const noexcept { return warning_.empty(); }
  const RealtimeGrants& grants() const noexcept { return grants_; }
  const LoopStats& stats() const noexcept { return *stats_; }
  std::chrono::nanoseconds period() const noexcept { return std::chrono::nanoseconds(period_ns_); }

 private:
  RealtimeLoop() = default;
  bool begin_run() noexcept;
  void sleep_until(std::int64_t deadline_ns) noexcept;
  void mark_steady() noexcept;
  void end_run() noexcept;

  void restore() noexcept;

  pid_t thread_ = 0;  // the thread open() configured, and the one run() must be called on
  std::int64_t period_ns_ = 0;
  fw::Tick steady_after_ = 0;
  std::unique_ptr<LoopStats> stats_;  // a 40 KB histogram: on the heap, allocated once at open
  PeriodTracker tracker_{0, 1};
  bool steady_ = false;
  long minor_faults_at_steady_ = 0;
  long major_faults_at_steady_ = 0;
  // What the thread had before open(), given back by the destructor.
  bool restore_scheduling_ = false;
  int saved_policy_ = 0;  // with its SCHED_RESET_ON_FORK flag
  int saved_priority_ = 0;
  bool restore_affinity_ = false;
  cpu_set_t saved_cpus_{};
  bool unlock_memory_ = false;
  bool owns_ = false;
  RealtimeGrants grants_;
  std::string warning_;
};

}  // namespace lever::board
