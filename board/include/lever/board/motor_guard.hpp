#pragma once
// The motor guard: a small process beside the lever that stops its motor when the lever cannot. It holds copies of
// the motor's own handles from the start (the driver's enable-line request, the PWM's duty_cycle and enable files)
// and waits on the lever's pidfd and on its loop's deadline; when the lever dies, or its loop has not stepped
// within the deadline, it drives the defined inactive state: the enable line deasserted, then duty 0 with the PWM
// enabled (a disabled PWM's output is not defined: the kernel's PWM documentation). No configuration is parsed and
// no process started on that path, and it only ever writes "off". It runs one SCHED_FIFO priority above the loop,
// so a loop spinning at its own priority on a single CPU cannot starve it. The lever, in turn, hears the guard end
// (SIGCHLD) and stops the motor itself. docs/board-motor.md, "The motor guard".
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::board {

// The motor's handles the guard keeps: file descriptors of this process, duplicated into the guard.
struct MotorGuardHandles {
  int duty_fd = -1;
  int enable_fd = -1;
  int enable_line_fd = -1;  // the enable line's request; -1: the driver has none
};

struct MotorGuardConfig {
  // The loop's last step older than this: the motor off. Above the firmware's own TIMING rule (timing.fault_after_ms,
  // 2 ms in the examples), so a loop the firmware would still tolerate is never cut; far below systemd's WatchdogSec.
  std::chrono::milliseconds deadline{10};
  // How often the guard looks: a missed deadline is acted on within deadline + check.
  std::chrono::milliseconds check{2};
  int fifo_priority = 0;  // the guard's SCHED_FIFO priority; 0: none (the loop runs without one either)
  // The program the guard runs as (`PROGRAM --motor-guard SPEC`): lever-fw itself, or a test binary.
  std::string program = "/proc/self/exe";
};

// What the lever and its guard share: one page, written by the lever's loop and by the guard.
struct MotorGuardShared {
  std::atomic<std::int64_t> last_step_ns{0};  // CLOCK_MONOTONIC of the loop's last step; 0: not started
  std::atomic<std::uint64_t> trips{0};        // deadlines the guard found missed
  std::atomic<bool> loop_ended{false};        // the loop left on purpose: no deadline any more
};
static_assert(std::atomic<std::int64_t>::is_always_lock_free && std::atomic<std::uint64_t>::is_always_lock_free);

class MotorGuard {
 public:
  // Forks and execs the guard (config.program --motor-guard SPEC), which copies the handles; returns once it runs
  // (it has opened the lever's pidfd and raised its priority) or fails naming why.
  static Result<MotorGuard> start(const MotorGuardConfig& config, const MotorGuardHandles& handles);

  MotorGuard(MotorGuard&&) noexcept;
  MotorGuard& operator=(MotorGuard&&) = delete;
  MotorGuard(const MotorGuard&) = delete;
  MotorGuard& operator=(const MotorGuard&) = delete;
  // The loop has ended on purpose (loop_ended(), or this destructor): no deadline any more; the guard stops the motor
  // again once this process has exited, and ends.
  ~MotorGuard();
  void loop_ended() noexcept { shared_->loop_ended.store(true); }

  // After each step the loop completed (its clock's reading at the step): one atomic store.
  void stepped(std::int64_t monotonic_ns) noexcept { shared_->last_step_ns.store(monotonic_ns); }
  // True once per deadline the guard found missed: the motor is off behind the lever's back, and what the lever
  // last wrote is no longer what the hardware holds.
  bool take_trip() noexcept;
  // The guard has ended (killed, crashed): this process must stop its motor itself. Async-signal-safe.
  static bool lost() noexcept;

  pid_t pid() const noexcept { return pid_; }
  // "motor guard pid 123: deadline 10 ms, checked every 2 ms, SCHED_FIFO 81", for the log line at start.
  const std::string& description() const noexcept { return description_; }

 private:
  MotorGuard(pid_t pid, MotorGuardShared* shared, std::string description) noexcept;
  pid_t pid_;
  MotorGuardShared* shared_;
  std::uint64_t trips_seen_ = 0;
  std::string description_;
};

// The guard process's main (lever-fw --motor-guard SPEC): exit 0 once the lever has ended and the motor is off,
// 1 when it could not hold on to the lever, 2 for a SPEC it cannot read.
int run_motor_guard(const char* spec);

}  // namespace lever::board
