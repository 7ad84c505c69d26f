#pragma once
// What the real-time loop asks of Linux: its period, a SCHED_FIFO priority, the CPUs it may run on, and
// memory locked and stack pre-faulted so that no page fault stalls a step.
#include <chrono>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lever/fw/tick.hpp"

namespace lever::board {

struct RealtimeConfig {
  std::chrono::nanoseconds period = std::chrono::milliseconds(1);  // the firmware's tick
  // SCHED_FIFO 1..99; 0 stays SCHED_OTHER. 80: above PREEMPT_RT's interrupt threads (50), which do their work
  // while the loop sleeps between steps, and as cyclictest is commonly run.
  int fifo_priority = 80;
  std::vector<unsigned> cpus;                     // the loop thread's CPUs; empty: wherever the scheduler puts it
  bool lock_memory = true;                        // mlockall(MCL_CURRENT | MCL_FUTURE)
  std::size_t prefault_stack_bytes = 256 * 1024;  // touched once at open, so the loop's stack is resident; 0: none
  fw::Tick steady_after_ticks = 100;              // page faults are counted from this tick on (start-up excluded)

  // Every problem, each naming its field; empty when the config can be opened.
  std::vector<std::string> validate() const;
};

// "2", "0,2-3": a CPU list as taskset and cyclictest's -a take it; empty when malformed.
std::optional<std::vector<unsigned>> parse_cpu_list(std::string_view text);

}  // namespace lever::board
