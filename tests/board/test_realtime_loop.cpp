// The real-time loop's logic, none of it timed: the latency histogram's percentiles, the tick each wake-up
// serves (made-up times), the core's timing fault seeing the skipped ticks, the config, and open() granting,
// refusing (unprivileged, in a child) and giving back what it set. How fast the loop wakes is a benchmark's
// business (bench/loop_bench.cpp), never a test's.
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "fork_child.hpp"
#include "lever/board/latency_histogram.hpp"
#include "lever/board/period_tracker.hpp"
#include "lever/board/realtime_loop.hpp"
#include "lever/fw/step_timing.hpp"
#include "skip.hpp"

using lever::board::LatencyHistogram;
using lever::board::LoopStats;
using lever::board::PeriodTracker;
using lever::board::RealtimeConfig;
using lever::board::RealtimeLoop;
using lever::fw::Tick;

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kMlockallIntercepted = true;
#else
constexpr bool kMlockallIntercepted = false;
#endif

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kUs = 1'000;

// No privileges asked: what a unit test may do on any machine.
RealtimeConfig plain() {
  RealtimeConfig c;
  c.fifo_priority = 0;
  c.lock_memory = false;
  c.prefault_stack_bytes = 64 * 1024;
  c.steady_after_ticks = 2;
  return c;
}

bool mentions(const std::vector<std::string>& problems, const std::string& text) {
  for (const auto& p : problems)
    if (p.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("LatencyHistogram: nearest-rank percentiles of 1 us bins, truncated as cyclictest does", "[loop]") {
  LatencyHistogram h;
  CHECK(h.percentile_us(0.99) == 0);
  for (int us = 0; us < 100; ++us) h.record_ns(us * kUs + 900);  // 0.9, 1.9, ... 99.9 us
  CHECK(h.count() == 100);
  CHECK(h.percentile_us(0.5) == 49);
  CHECK(h.percentile_us(0.99) == 98);
  CHECK(h.percentile_us(1.0) == 99);
  CHECK(h.max_us() == 99);
  h.record_ns(-5 * kUs);  // an early wake-up cannot be, but must not index below the first bin
  CHECK(h.percentile_us(0.0) == 0);

  LatencyHistogram three;  // a rank between two samples rounds up: the median of three is the second
  for (int us = 1; us <= 3; ++us) three.record_ns(us * kUs);
  CHECK(three.percentile_us(0.5) == 2);
  CHECK(three.percentile_us(0.99) == 3);

  LatencyHistogram late;
  for (int i = 0; i < 98; ++i) late.record_ns(10 * kUs);
  late.record_ns(7 * kMs);  // past the last bin
  late.record_ns(9 * kMs + 300 * kUs);
  CHECK(late.overflows() == 2);
  CHECK(late.percentile_us(0.98) == 10);
  CHECK(late.percentile_us(0.99) == 9300);  // its rank is an overflow: the worst is the best that can be said
  CHECK(late.max_us() == 9300);

  LatencyHistogram imported;
  imported.add_us(3, 60);
  imported.add_us(40, 40);
  imported.add_us(6000, 1);
  imported.note_max_us(6123);
  CHECK(imported.count() == 101);
  CHECK(imported.percentile_us(0.5) == 3);
  CHECK(imported.percentile_us(0.99) == 40);
  CHECK(imported.max_us() == 6123);

  LatencyHistogram merged = three;
  merged.add(late);
  CHECK(merged.count() == 103);
  CHECK(merged.overflows() == 2);
  CHECK(merged.percentile_us(0.5) == 10);
  CHECK(merged.max_us() == 9300);
}

TEST_CASE("PeriodTracker: each wake-up serves the latest tick due, skipping the ones missed whole", "[loop]") {
  LoopStats stats;
  PeriodTracker t(100 * kMs, kMs);
  CHECK(t.deadline_ns() == 101 * kMs);

  CHECK(t.woke(101 * kMs + 20 * kUs, stats) == 1);
  t.step_done(101 * kMs + 50 * kUs, stats);
  CHECK(t.deadline_ns() == 102 * kMs);

  // 2.5 periods late: ticks 2 and 3 are gone, tick 4 is served; the latency is counted from tick 2's time.
  CHECK(t.woke(104 * kMs + 500 * kUs, stats) == 4);
  CHECK(stats.late_wakes == 1);
  CHECK(stats.skipped_periods == 2);
  CHECK(stats.wake_latency.max_us() == 2500);
  t.step_done(104 * kMs + 600 * kUs, stats);
  CHECK(t.deadline_ns() == 105 * kMs);

  // A step longer than a period, then a wake-up late by less than one: no tick skipped.
  CHECK(t.woke(105 * kMs, stats) == 5);
  t.step_done(106 * kMs + 200 * kUs, stats);
  CHECK(stats.long_steps == 1);
  CHECK(stats.worst_step_ns == kMs + 200 * kUs);
  CHECK(t.woke(106 * kMs + 200 * kUs, stats) == 6);
  t.step_done(106 * kMs + 300 * kUs, stats);

  // Late by exactly one period: that tick is skipped.
  CHECK(t.woke(108 * kMs, stats) == 8);
  t.step_done(108 * kMs + 10 * kUs, stats);
  CHECK(stats.late_wakes == 2);
  CHECK(stats.skipped_periods == 3);
  CHECK(stats.steps == 5);
  CHECK(stats.overruns() == 3);
  CHECK(stats.wake_latency.count() == 5);
  // Step durations 30, 100, 1200, 100 and 10 µs.
  CHECK(stats.step_duration.count() == 5);
  CHECK(stats.step_duration.percentile_us(0.5) == 100);
  CHECK(stats.step_duration.max_us() == 1200);
}

TEST_CASE("PeriodTracker: the ticks it serves show the core's step timing the gaps it must fault on", "[loop]") {
  LoopStats stats;
  PeriodTracker t(0, kMs);
  lever::fw::StepTiming timing;
  const auto serve = [&](std::int64_t woke_at) {
    const Tick tick = t.woke(woke_at, stats);
    timing.begin(tick);
    t.step_done(woke_at + 10 * kUs, stats);
  };
  serve(1 * kMs);
  serve(2 * kMs + 5 * kUs);
  CHECK(timing.stats().overruns == 0);
  serve(4 * kMs + 100 * kUs);  // tick 3 missed: an interval of 2 ticks, an overrun
  CHECK(timing.stats().overruns == 1);
  CHECK_FALSE(timing.violated());
  serve(11 * kMs + 1 * kUs);  // ticks 5 to 10 missed: an interval of 7 ticks, past the 2-tick bound
  CHECK(timing.violated());
  CHECK(timing.stats().worst_interval == 7);
  CHECK(timing.stats().clock_faults == 0);
}

TEST_CASE("RealtimeConfig: problems name their field; CPU lists parse as taskset writes them", "[loop]") {
  CHECK(plain().validate().empty());
  RealtimeConfig c;
  c.period = std::chrono::microseconds(10);
  c.fifo_priority = 120;
  c.cpus = {CPU_SETSIZE + 1u};
  c.prefault_stack_bytes = 64u << 20;
  const auto problems = c.validate();
  CHECK(mentions(problems, "period: 10000 ns"));
  CHECK(mentions(problems, "fifo_priority: 120"));
  CHECK(mentions(problems, "cpus: " + std::to_string(CPU_SETSIZE + 1)));
  CHECK(mentions(problems, "prefault_stack_bytes:"));
  const auto refused = RealtimeLoop::open(c);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("real-time config: period:") == 0);

  using V = std::vector<unsigned>;
  CHECK(lever::board::parse_cpu_list("2") == V{2});
  CHECK(lever::board::parse_cpu_list("0,2-4") == V{0, 2, 3, 4});
  CHECK_FALSE(lever::board::parse_cpu_list(""));
  CHECK_FALSE(lever::board::parse_cpu_list("1,"));
  CHECK_FALSE(lever::board::parse_cpu_list("3-1"));
  CHECK_FALSE(lever::board::parse_cpu_list("a"));
}

TEST_CASE("RealtimeLoop: run serves increasing ticks from 1 until stopped, and counts what it served", "[loop]") {
  auto opened = RealtimeLoop::open(plain());
  REQUIRE(opened.ok());
  RealtimeLoop& loop = opened.value();
  CHECK(loop.privileged());  // nothing was asked
  CHECK(loop.grants().stack_prefaulted_bytes == 64 * 1024);
  std::vector<Tick> ticks;
  ticks.reserve(64);
  std::stop_source stop;
  REQUIRE(loop.run(
      [&](Tick tick) {
        ticks.push_back(tick);
        if (ticks.size() == 10) stop.request_stop();
      },
      stop.get_token()));
  REQUIRE(ticks.size() == 10);
  CHECK(ticks.front() >= 1);
  for (std::size_t i = 1; i < ticks.size(); ++i) CHECK(ticks[i] > ticks[i - 1]);  // a busy machine skips some
  CHECK(loop.stats().steps == 10);
  CHECK(loop.stats().wake_latency.count() == 10);
  CHECK(loop.stats().skipped_periods == ticks.back() - 10);  // ticks count from 1, the skipped ones too
}

// The steady part of the loop (sleep, clock reads, the step) touches no page it has not touched before. Without
// mlockall the pages stay resident only because nothing evicts them in a run this short; the board asks for
// lock_memory as well (docs/board-realtime.md).
TEST_CASE("RealtimeLoop: the steady part takes no page fault", "[loop]") {
  RealtimeConfig c = plain();
  c.steady_after_ticks = 10;
  auto opened = RealtimeLoop::open(c);
  REQUIRE(opened.ok());
  RealtimeLoop& loop = opened.value();
  std::uint64_t sum = 0;
  std::stop_source stop;
  REQUIRE(loop.run(
      [&](Tick tick) {
        sum += tick;
        if (tick >= 200) stop.request_stop();
      },
      stop.get_token()));
  REQUIRE(loop.stats().minor_faults_steady.has_value());
  CHECK(*loop.stats().minor_faults_steady == 0);
  CHECK(loop.stats().major_faults_steady == 0);
  CHECK(sum > 0);
}

TEST_CASE("RealtimeLoop: run refuses a thread other than the one open() configured", "[loop]") {
  auto opened = RealtimeLoop::open(plain());
  REQUIRE(opened.ok());
  bool ran = true;
  int steps = 0;
  std::thread other([&] { ran = opened.value().run([&](Tick) { ++steps; }, std::stop_token{}); });
  other.join();
  CHECK_FALSE(ran);
  CHECK(steps == 0);
}

TEST_CASE("RealtimeLoop: the thread gets its CPUs and scheduling back when the loop goes", "[loop]") {
  cpu_set_t before;
  REQUIRE(::sched_getaffinity(0, sizeof before, &before) == 0);
  unsigned first_cpu = 0;
  while (!CPU_ISSET(first_cpu, &before)) ++first_cpu;
  RealtimeConfig c = plain();
  c.cpus = {first_cpu};
  c.fifo_priority = 10;  // granted only with privileges; either way it must be undone
  {
    auto opened = RealtimeLoop::open(c);
    REQUIRE(opened.ok());
    cpu_set_t during;
    REQUIRE(::sched_getaffinity(0, sizeof during, &during) == 0);
    CHECK(CPU_COUNT(&during) == 1);
    CHECK(CPU_ISSET(first_cpu, &during));
    CHECK((::sched_getscheduler(0) & ~SCHED_RESET_ON_FORK) ==
          (opened.value().grants().fifo_priority > 0 ? SCHED_FIFO : SCHED_OTHER));
  }
  cpu_set_t after;
  REQUIRE(::sched_getaffinity(0, sizeof after, &after) == 0);
  CHECK(CPU_EQUAL(&before, &after));
  CHECK(::sched_getscheduler(0) == SCHED_OTHER);
}

namespace {

constexpr int kCannotRaiseLimit = 77;

// open() asking SCHED_FIFO 80 and locked memory in a child that has neither privilege, RLIMIT_RTPRIO at
// rtprio_limit: the child's exit status says which expectation failed (0: none).
int unprivileged_open(rlim_t rtprio_limit) {
  return lever::test::wait_status_of_child([&] {
    // Lowering limits needs no privilege; giving up root drops CAP_SYS_NICE and CAP_IPC_LOCK, which would
    // override them.
    const rlimit rtprio{rtprio_limit, rtprio_limit};
    const rlimit memlock{0, 0};
    if (::setrlimit(RLIMIT_RTPRIO, &rtprio) != 0) return kCannotRaiseLimit;  // no CAP_SYS_RESOURCE to raise it
    if (::setrlimit(RLIMIT_MEMLOCK, &memlock) != 0) return 70;
    if (::geteuid() == 0 && ::setuid(65534) != 0) return 71;
    RealtimeConfig c = plain();
    c.fifo_priority = 80;
    c.lock_memory = true;
    auto opened = RealtimeLoop::open(c);
    if (!opened) return 1;
    const RealtimeLoop& loop = opened.value();
    const std::string& w = loop.warning();
    if (loop.privileged()) return 2;
    if (w.find("SCHED_FIFO 80 refused") == std::string::npos) return 3;
    // AddressSanitizer replaces mlockall with a no-op that succeeds: the refusal cannot be seen under it.
    if (w.find("mlockall refused") == std::string::npos && !kMlockallIntercepted) return 4;
    const int expected = static_cast<int>(rtprio_limit);
    if (loop.grants().fifo_priority != expected) return 5;
    if (w.find(expected > 0 ? "running SCHED_FIFO 10" : "running SCHED_OTHER") == std::string::npos) return 6;
    if (loop.grants().memory_locked && !kMlockallIntercepted) return 7;
    int steps = 0;
    std::stop_source stop;
    if (!opened.value().run(
            [&](Tick) {
              if (++steps == 3) stop.request_stop();
            },
            stop.get_token()))
      return 8;
    return steps == 3 ? 0 : 9;
  });
}

}  // namespace

TEST_CASE("RealtimeLoop: without privileges or RLIMIT_RTPRIO it warns once and runs SCHED_OTHER", "[loop]") {
  const int status = unprivileged_open(0);  // lowering a limit needs no privilege
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}

TEST_CASE("RealtimeLoop: without privileges, RLIMIT_RTPRIO 10, it warns once and runs SCHED_FIFO 10", "[loop]") {
  const int status = unprivileged_open(10);
  REQUIRE(WIFEXITED(status));
  if (WEXITSTATUS(status) == kCannotRaiseLimit)
    LEVER_SKIP("RLIMIT_RTPRIO's hard limit is below 10 and this process may not raise it (no CAP_SYS_RESOURCE)");
  CHECK(WEXITSTATUS(status) == 0);
}
