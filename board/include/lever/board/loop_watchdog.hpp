#pragma once
// The watchdogs of a board's control loop: the service manager's (systemd's WatchdogSec=, through libsystemd's
// sd_notify) and, optionally, a hardware one (/dev/watchdogN), both fed only while the loop advances.
//
// The loop calls advanced(tick) each step: one relaxed atomic store, no system call, nothing that can block.
// A thread of its own looks every check_interval(): when the loop's tick moved since it last looked, it sends
// WATCHDOG=1 and writes the hardware watchdog; when it did not, it sends nothing. So a loop stuck in a step (a
// hung write, a lock, a stopped process) stops the feeding, and the service manager kills the process
// WatchdogSec after the last feed, at most WatchdogSec + check_interval() after the loop stopped: the thread
// only ever feeds what the loop did. On that kill (WatchdogSignal=SIGABRT) the motor-stop handlers
// (motor_stop_signals.hpp) stop the motor in the process, and ExecStopPost's lever-fw --motor-off again after it.
// READY=1 goes out once the loop has advanced: the lever has booted and can be armed.
//
// Start it before the loop makes its thread real-time: the thread then keeps the service's own scheduling
// (SCHED_FIFO 50 in lever-fw@.service) instead of being reset to SCHED_OTHER, and a busy board does not starve it
// into a false kill.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "lever/board/result.hpp"

namespace lever::board {

struct LoopWatchdogConfig {
  // A hardware watchdog device (/dev/watchdog0); empty: none. It resets the board when nothing feeds it for
  // device_timeout: the last resort, when neither the process nor its service manager can act.
  std::string device;
  std::chrono::seconds device_timeout{2};  // 1..60 s; drivers count in whole seconds
};

class LoopWatchdog {
 public:
  // Reads the service manager's watchdog interval (WATCHDOG_USEC, for this process) and opens the device, if
  // any, setting its timeout; then starts the thread. Without a service watchdog or a device the thread still
  // sends READY=1 (when NOTIFY_SOCKET is set) and nothing else.
  static Result<LoopWatchdog> open(const LoopWatchdogConfig& config);

  LoopWatchdog(LoopWatchdog&&) noexcept;
  LoopWatchdog& operator=(LoopWatchdog&&) noexcept;
  LoopWatchdog(const LoopWatchdog&) = delete;
  LoopWatchdog& operator=(const LoopWatchdog&) = delete;
  // stop(), if not done.
  ~LoopWatchdog();

  // The loop, each step. Lock-free, wait-free, no system call.
  void advanced(std::uint64_t tick) noexcept;

  // A deliberate end: STOPPING=1, the thread joined, and the hardware watchdog disarmed (its magic close).
  void stop() noexcept;

  // The service manager's interval (zero: none) and how often the thread looks: a quarter of it, or of the
  // device's timeout when that is shorter; 100 ms with neither.
  std::chrono::microseconds service_interval() const noexcept;
  std::chrono::microseconds check_interval() const noexcept;
  // The longest a stuck loop goes on before the service manager acts: service_interval + check_interval.
  std::chrono::microseconds kill_bound() const noexcept;
  // Feeds sent (WATCHDOG=1 or device writes), for logs and tests.
  std::uint64_t feeds() const noexcept;
  // "service watchdog 200 ms, checked every 50 ms; /dev/watchdog0 2 s", for the log line at start.
  std::string description() const;

 private:
  struct Shared;
  explicit LoopWatchdog(std::unique_ptr<Shared> shared);
  std::unique_ptr<Shared> shared_;
  std::jthread thread_;
};

}  // namespace lever::board
