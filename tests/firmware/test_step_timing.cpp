// The timing budget (docs/firmware.md, "Timing budget"): late intervals and long steps are lost time; more than
// fault_after - 1 periods of it within any window latches TIMING, one interval above fault_after at once.
#include <catch2/catch.hpp>

#include "fake_hal.hpp"
#include "lever/fw/lever.hpp"
#include "lever/fw/step_timing.hpp"
#include "lever_rig.hpp"

using namespace lever;
using namespace lever::fw;

namespace {

// Steps `timing` at every tick from `from` to `to`, each taking `step_ns`; returns the first tick whose begin
// found the budget broken (0: none).
Tick run(StepTiming& timing, Tick from, Tick to, std::uint64_t step_ns = 10'000) {
  for (Tick t = from; t <= to; ++t) {
    timing.begin(t);
    if (timing.violated()) return t;
    timing.step_took(step_ns);
  }
  return 0;
}

}  // namespace

TEST_CASE("timing: the defaults are the derived budget: one lost period per 68 ms, steps up to 100 us free",
          "[firmware][timing]") {
  const StepTiming::Config c{};
  CHECK(c.fault_after == 2);
  CHECK(c.window == 68);
  CHECK(c.long_step_us == 100u);
}

TEST_CASE("timing: one late tick is within the budget, a second within the window is not", "[firmware][timing]") {
  StepTiming timing;
  REQUIRE(run(timing, 1, 100) == 0);
  timing.begin(102);  // one period lost
  CHECK_FALSE(timing.violated());
  CHECK(timing.stats().overruns == 1u);
  CHECK(timing.lost_in_window_us() == 1000u);
  SECTION("the next one 67 ticks later: still in the window") {
    REQUIRE(run(timing, 103, 167) == 0);
    timing.begin(169);
    CHECK(timing.violated());
  }
  SECTION("the next one 68 ticks later: the first has left the window") {
    REQUIRE(run(timing, 103, 168) == 0);
    timing.begin(170);
    CHECK_FALSE(timing.violated());
    CHECK(timing.lost_in_window_us() == 1000u);
  }
  SECTION("one every 69 ticks for a long while: within the budget for good") {
    Tick t = 102;
    for (int i = 0; i < 50; ++i) {
      REQUIRE(run(timing, t + 1, t + 67) == 0);
      t += 69;
      timing.begin(t);
      REQUIRE_FALSE(timing.violated());
    }
    CHECK(timing.stats().overruns == 51u);
  }
}

TEST_CASE("timing: an interval longer than fault_after latches at once, whatever the window held",
          "[firmware][timing]") {
  StepTiming timing;
  REQUIRE(run(timing, 1, 100) == 0);
  timing.begin(103);  // two periods lost
  CHECK(timing.violated());
  CHECK(timing.stats().worst_interval == 3u);
}

TEST_CASE("timing: long steps are lost time: sustained, over budget; once, not", "[firmware][timing]") {
  StepTiming timing;
  SECTION("150 us each: the seventh makes 1050 us in the window") {
    CHECK(run(timing, 1, 200, 150'000) == 8);
    CHECK(timing.stats().long_steps == 7u);
  }
  SECTION("a single 900 us step, then 10 us ones: within the budget") {
    timing.begin(1);
    timing.step_took(900'000);
    CHECK(run(timing, 2, 200) == 0);
    CHECK(timing.stats().long_steps == 1u);
  }
  SECTION("steps of 100 us, at the threshold, cost nothing") { CHECK(run(timing, 1, 500, 100'000) == 0); }
  SECTION("a late tick and a 150 us step in one window: over") {
    REQUIRE(run(timing, 1, 50) == 0);
    timing.begin(52);
    REQUIRE_FALSE(timing.violated());
    timing.step_took(150'000);
    timing.begin(53);
    CHECK(timing.violated());
  }
}

TEST_CASE("timing: a wide budget (the emulator's configs) still latches a single gap above it", "[firmware][timing]") {
  StepTiming::Config c;
  c.fault_after = 500;
  StepTiming timing(c);
  REQUIRE(run(timing, 1, 10) == 0);
  Tick t = 10;
  for (int i = 0; i < 40; ++i) {  // 4 ms stalls every 10 ms: about 27 ms lost per 68 ms window, within 499
    REQUIRE(run(timing, t + 1, t + 5) == 0);
    t += 10;
    timing.begin(t);
    REQUIRE_FALSE(timing.violated());
  }
  timing.begin(t + 502);
  CHECK(timing.violated());
}

namespace {

// A TOP whose board clock says each step took `step_ns`.
struct ClockedHal : test::FakeHal<> {
  using test::FakeHal<>::FakeHal;
  std::uint64_t clock_ns = 0;
  std::uint64_t step_ns = 10'000;
  bool starting = true;
  std::uint64_t monotonic_ns() {
    clock_ns += starting ? 0 : step_ns;  // the core reads the clock at the start and at the end of each step
    starting = !starting;
    return clock_ns;
  }
};
static_assert(HasStepClock<ClockedHal>);

}  // namespace

TEST_CASE("timing: steps that run long take an armed lever to TIMING through its own step clock",
          "[firmware][timing][lever]") {
  test::CanBus bus;
  ClockedHal hal(bus);
  TopLever<ClockedHal> top(hal, test::rig_config(protocol::Role::top));
  Tick now = 1;
  auto step = [&] {
    hal.force_.reading = ForceReading{0, now, false};
    bus.inject(protocol::pack(protocol::HeartbeatMessage{}, 0, protocol::Role::hsi));
    top.step(now++);
  };
  for (int i = 0; i < 50; ++i) step();
  bus.inject(protocol::pack(protocol::CommandMessage{}, 0));  // arm
  step();
  REQUIRE(top.supervisor().armed());
  for (int i = 0; i < 100; ++i) step();
  REQUIRE(top.supervisor().armed());
  hal.step_ns = 300'000;  // 30 % of the period, every step: 0.3 ms of delay the loops were not designed for
  Tick faulted_at = 0;
  for (int i = 0; i < 20 && faulted_at == 0; ++i) {
    step();
    if (top.supervisor().state() == LeverState::fault) faulted_at = now - 1;
  }
  REQUIRE(faulted_at != 0);
  CHECK(has(top.supervisor().latched(), Fault::timing));
  CHECK(top.timing().stats().long_steps == 5u);  // 1200 us in the window after four, judged at the fifth's begin
  CHECK_FALSE(hal.motor_.last.enable);
}
