#include "motor_stop_registry.hpp"

#include <sched.h>
#include <time.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>

#include "motor_lines.hpp"
#include "sysfs_write.hpp"

namespace lever::board {

namespace {

struct Slot {
  std::atomic<bool> taken{false};
  std::atomic<int> duty_fd{-1};
  std::atomic<int> enable_fd{-1};
  std::atomic<int> enable_line_fd{-1};
  std::atomic<pid_t> owner{0};
  std::atomic<pid_t> commanding{0};  // the thread in a command of this motor, 0: none
};

std::array<Slot, kMaxStoppableMotors> slots;
std::atomic<int> stops_running{0};
std::atomic<bool> latched{false};
std::atomic<bool> exit_hook_installed{false};

// Lock-free atomics are what makes the registry usable from a signal handler.
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free &&
              std::atomic<pid_t>::is_always_lock_free);

std::int64_t monotonic_ms() noexcept {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000 + now.tv_nsec / 1'000'000;
}

// Until the command in progress on another thread has ended, or the wait's bound.
void wait_for_command(const Slot& slot, pid_t this_thread, std::int64_t deadline_ms) noexcept {
  for (;;) {
    const pid_t in_command = slot.commanding.load();
    if (in_command == 0 || in_command == this_thread || monotonic_ms() > deadline_ms) return;
    ::sched_yield();
  }
}

void stop_slots(bool only_own) noexcept {
  const int saved_errno = errno;
  // The latch before looking at the commands, each command's mark before it looks at the latch (both sequentially
  // consistent): a command either sees the latch and writes nothing but a stop, or is seen here and waited for.
  latched.store(true);
  stops_running.fetch_add(1);
  const pid_t self = only_own ? ::getpid() : 0;
  const pid_t this_thread = ::gettid();
  const std::int64_t deadline_ms = monotonic_ms() + kCommandWaitMs;
  for (Slot& slot : slots) {
    if (only_own && slot.owner.load() != self) continue;
    wait_for_command(slot, this_thread, deadline_ms);
    const int line = slot.enable_line_fd.load();
    const int duty = slot.duty_fd.load();
    const int enable = slot.enable_fd.load();
    if (line >= 0) set_line_request(line, false);
    // The inactive state, duty 0 with the channel enabled: a disabled PWM's output is undefined (SysfsPwm::stop).
    if (duty >= 0) write_decimal(duty, 0);
    if (enable >= 0) write_decimal(enable, 1);
  }
  stops_running.fetch_sub(1);
  errno = saved_errno;
}

// At exit() a motor whose destructor will not run (one on main's stack, when something calls exit()) still
// stops. Only the process that opened it: a child forked without exec shares the files, and its exit must not
// stop its parent's motor.
extern "C" void stop_motors_at_exit() { stop_slots(true); }

}  // namespace

int register_motor_stop(int duty_fd, int enable_fd, int enable_line_fd) noexcept {
  if (!exit_hook_installed.exchange(true)) std::atexit(stop_motors_at_exit);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    Slot& slot = slots[i];
    bool expected = false;
    if (!slot.taken.compare_exchange_strong(expected, true)) continue;
    slot.owner.store(::getpid());
    slot.duty_fd.store(duty_fd);
    slot.enable_fd.store(enable_fd);
    slot.enable_line_fd.store(enable_line_fd);
    return static_cast<int>(i);
  }
  return -1;
}

void unregister_motor_stop(int slot_index) noexcept {
  if (slot_index < 0 || static_cast<std::size_t>(slot_index) >= slots.size()) return;
  Slot& slot = slots[static_cast<std::size_t>(slot_index)];
  slot.duty_fd.store(-1);
  slot.enable_fd.store(-1);
  slot.enable_line_fd.store(-1);
  // A stop on another thread may hold the old numbers; it is a few writes long. A stop interrupting this very
  // thread has finished before this line runs again.
  while (stops_running.load() != 0) ::sched_yield();
  slot.owner.store(0);
  slot.taken.store(false);
}

void begin_motor_command(int slot_index) noexcept {
  if (slot_index < 0 || static_cast<std::size_t>(slot_index) >= slots.size()) return;
  slots[static_cast<std::size_t>(slot_index)].commanding.store(::gettid());
}

void end_motor_command(int slot_index) noexcept {
  if (slot_index < 0 || static_cast<std::size_t>(slot_index) >= slots.size()) return;
  slots[static_cast<std::size_t>(slot_index)].commanding.store(0);
}

void emergency_stop_registered_motors() noexcept { stop_slots(false); }

bool emergency_stop_latched() noexcept { return latched.load(); }

}  // namespace lever::board
