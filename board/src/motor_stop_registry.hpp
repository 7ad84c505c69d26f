#pragma once
// Every open PwmMotor's two PWM files and its enable line's request, kept where a signal handler can reach them:
// the process-wide emergency stop deasserts the line (one ioctl), then writes duty 0 and enable 1 to the PWM (the
// inactive state: SysfsPwm::stop), with pwrite.
#include <cstddef>

namespace lever::board {

inline constexpr std::size_t kMaxStoppableMotors = 8;

// A slot for a motor's duty_cycle and enable files; -1 when all are taken. The first registration also has
// the process stop its motors at exit().
int register_motor_stop(int duty_fd, int enable_fd, int enable_line_fd) noexcept;
// Frees the slot, after any emergency stop running on another thread is through with it (the fds may be
// closed and their numbers reused right after).
void unregister_motor_stop(int slot) noexcept;

// A motor command's writes go between these two. An emergency stop waits for a command in progress on another
// thread to end (at most kCommandWaitMs: a write stuck in the kernel must not hold the stop for ever) before it
// writes, so that none of the command's writes lands after its own; the command, seeing the latch at its end,
// stops the motor itself. A command interrupted by the stop on its own thread cannot be waited for: it stops the
// motor again at its end, unless the process dies first (a crash handler), when nothing of it is written.
inline constexpr long kCommandWaitMs = 100;
void begin_motor_command(int slot) noexcept;
void end_motor_command(int slot) noexcept;

// Async-signal-safe: atomics, clock_gettime, sched_yield and pwrite only; errno is preserved. Latches: motors stay
// stopped afterwards.
void emergency_stop_registered_motors() noexcept;
bool emergency_stop_latched() noexcept;

}  // namespace lever::board
