#include "lever/board/realtime_loop.hpp"

#include <alloca.h>
#include <pthread.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <utility>

#include "lever/board/config_error.hpp"

namespace lever::board {

namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;
// Left untouched below the pre-faulted part: the frames of whatever runs the loop, and the signal handlers.
constexpr std::size_t kStackReserve = 64 * 1024;

std::string limit_text(rlim_t value) {
  return value == RLIM_INFINITY ? std::string("unlimited") : std::to_string(value);
}

// Room left on this thread's stack below the current frame.
std::size_t stack_room() noexcept {
  pthread_attr_t attr;
  if (::pthread_getattr_np(::pthread_self(), &attr) != 0) return 0;
  void* low = nullptr;
  std::size_t size = 0;
  const int rc = ::pthread_attr_getstack(&attr, &low, &size);
  ::pthread_attr_destroy(&attr);
  if (rc != 0) return 0;
  const char here = 0;
  const auto top = reinterpret_cast<std::uintptr_t>(&here);
  const auto bottom = reinterpret_cast<std::uintptr_t>(low);
  return top > bottom ? top - bottom : 0;
}

// Touches one byte per page of `bytes` below this frame, so that the loop's deepest calls find their stack
// pages resident (and locked, under MCL_FUTURE) instead of faulting them in mid-step.
[[gnu::noinline]] void prefault_stack(std::size_t bytes) noexcept {
  const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  auto* stack = static_cast<volatile unsigned char*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += page) stack[i] = 0;
}

void append(std::string& warning, const std::string& text) {
  if (!warning.empty()) warning += "; ";
  warning += text;
}

}  // namespace

Result<RealtimeLoop> RealtimeLoop::open(const RealtimeConfig& config) {
  if (const auto problems = config.validate(); !problems.empty()) return config_error("real-time config", problems);
  RealtimeLoop loop;
  loop.thread_ = ::gettid();
  loop.period_ns_ = config.period.count();
  loop.steady_after_ = config.steady_after_ticks;
  loop.stats_ = std::make_unique<LoopStats>();
  loop.owns_ = true;  // from here on, the destructor undoes what was done

  if (!config.cpus.empty()) {
    cpu_set_t wanted;
    CPU_ZERO(&wanted);
    for (const unsigned cpu : config.cpus) CPU_SET(cpu, &wanted);
    if (::sched_getaffinity(loop.thread_, sizeof loop.saved_cpus_, &loop.saved_cpus_) != 0 ||
        ::sched_setaffinity(loop.thread_, sizeof wanted, &wanted) != 0) {
      const int err = errno;
      std::string list;
      for (const unsigned cpu : config.cpus) list += (list.empty() ? "" : ",") + std::to_string(cpu);
      return Error{"real-time cpus: cannot run on " + list +
                       " (not online, or outside this process's cpuset): " + std::strerror(err),
                   err};
    }
    loop.restore_affinity_ = true;
    loop.grants_.cpus = config.cpus;
  }

  if (config.lock_memory) {
    if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      loop.unlock_memory_ = true;
      loop.grants_.memory_locked = true;
    } else {
      const int err = errno;
      rlimit memlock{};
      ::getrlimit(RLIMIT_MEMLOCK, &memlock);
      append(loop.warning_, std::string("mlockall refused (") + std::strerror(err) +
                                "; needs CAP_IPC_LOCK or an RLIMIT_MEMLOCK above the process's size, which is " +
                                limit_text(memlock.rlim_cur) + " bytes), so page faults may stall a step");
    }
  }

  if (config.prefault_stack_bytes > 0) {
    const std::size_t room = stack_room();
    const std::size_t usable = room > kStackReserve ? room - kStackReserve : 0;
    const std::size_t bytes = std::min(config.prefault_stack_bytes, usable);
    prefault_stack(bytes);
    loop.grants_.stack_prefaulted_bytes = bytes;
    if (bytes < config.prefault_stack_bytes) {
      append(loop.warning_, "stack pre-faulted over " + std::to_string(bytes) + " of the " +
                                std::to_string(config.prefault_stack_bytes) + " bytes asked (the thread's stack has " +
                                std::to_string(room) + " left)");
    }
  }
  // Raised last: locking memory faults in every page the process maps (its threads' stacks too), which at the
  // loop's priority would take the CPU from another lever's loop at the same priority on a one-core board.
  if (config.fifo_priority > 0) {
    sched_param saved{};
    loop.saved_policy_ = ::sched_getscheduler(loop.thread_);
    ::sched_getparam(loop.thread_, &saved);
    loop.saved_priority_ = saved.sched_priority;
    int granted = 0;
    sched_param wanted{};
    wanted.sched_priority = config.fifo_priority;
    if (::sched_setscheduler(loop.thread_, SCHED_FIFO | SCHED_RESET_ON_FORK, &wanted) == 0) {
      granted = config.fifo_priority;
    } else {
      const int err = errno;
      // Unprivileged, RLIMIT_RTPRIO may still allow a lower real-time priority: better than none.
      rlimit rtprio{};
      ::getrlimit(RLIMIT_RTPRIO, &rtprio);
      const auto allowed = static_cast<int>(rtprio.rlim_cur == RLIM_INFINITY ? 0 : rtprio.rlim_cur);
      sched_param lower{};
      lower.sched_priority = allowed;
      if (allowed > 0 && allowed < config.fifo_priority &&
          ::sched_setscheduler(loop.thread_, SCHED_FIFO | SCHED_RESET_ON_FORK, &lower) == 0) {
        granted = allowed;
      }
      append(loop.warning_, "SCHED_FIFO " + std::to_string(config.fifo_priority) + " refused (" + std::strerror(err) +
                                "; needs CAP_SYS_NICE or RLIMIT_RTPRIO >= " + std::to_string(config.fifo_priority) +
                                ", which is " + limit_text(rtprio.rlim_cur) + "), running " +
                                (granted > 0 ? "SCHED_FIFO " + std::to_string(granted) : std::string("SCHED_OTHER")));
    }
    loop.restore_scheduling_ = granted > 0;
    loop.grants_.fifo_priority = granted;
  }

  if (!loop.warning_.empty()) loop.warning_ = "real-time loop: " + loop.warning_;
  return loop;
}

RealtimeLoop::RealtimeLoop(RealtimeLoop&& other) noexcept
    : thread_(other.thread_),
      period_ns_(other.period_ns_),
      steady_after_(other.steady_after_),
      stats_(std::move(other.stats_)),
      tracker_(other.tracker_),
      steady_(other.steady_),
      minor_faults_at_steady_(other.minor_faults_at_steady_),
      major_faults_at_steady_(other.major_faults_at_steady_),
      restore_scheduling_(other.restore_scheduling_),
      saved_policy_(other.saved_policy_),
      saved_priority_(other.saved_priority_),
      restore_affinity_(other.restore_affinity_),
      saved_cpus_(other.saved_cpus_),
      unlock_memory_(other.unlock_memory_),
      owns_(std::exchange(other.owns_, false)),
      grants_(std::move(other.grants_)),
      warning_(std::move(other.warning_)) {}

RealtimeLoop::~RealtimeLoop() { restore(); }

void RealtimeLoop::restore() noexcept {
  if (!owns_) return;
  owns_ = false;
  if (restore_scheduling_) {
    sched_param saved{};
    saved.sched_priority = saved_priority_;
    ::sched_setscheduler(thread_, saved_policy_, &saved);
  }
  if (restore_affinity_) ::sched_setaffinity(thread_, sizeof saved_cpus_, &saved_cpus_);
  if (unlock_memory_) ::munlockall();
}

bool RealtimeLoop::begin_run() noexcept {
  if (!owns_ || ::gettid() != thread_) return false;
  *stats_ = LoopStats{};
  steady_ = false;
  // Deadlines on whole multiples of the period: loops on one machine keep the same phase however they were
  // started, so a closed loop of several processes in virtual time (the kernel rig) repeats run after run.
  const std::int64_t now = monotonic_ns();
  tracker_ = PeriodTracker(now - now % period_ns_, period_ns_);
  return true;
}

void RealtimeLoop::sleep_until(std::int64_t deadline_ns) noexcept {
  const timespec deadline{static_cast<time_t>(deadline_ns / kNsPerS), static_cast<long>(deadline_ns % kNsPerS)};
  // A signal handler interrupts the sleep; the deadline is absolute, so sleeping again loses nothing.
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
}

void RealtimeLoop::mark_steady() noexcept {
  rusage usage{};
  ::getrusage(RUSAGE_THREAD, &usage);
  minor_faults_at_steady_ = usage.ru_minflt;
  major_faults_at_steady_ = usage.ru_majflt;
  steady_ = true;
}

void RealtimeLoop::end_run() noexcept {
  if (!steady_) return;
  rusage usage{};
  ::getrusage(RUSAGE_THREAD, &usage);
  stats_->minor_faults_steady = usage.ru_minflt - minor_faults_at_steady_;
  stats_->major_faults_steady = usage.ru_majflt - major_faults_at_steady_;
}

}  // namespace lever::board
