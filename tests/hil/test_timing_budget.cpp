// The timing budget in the whole simulated testbed: patterns of late ticks (`tick-late@T+D`: a lever's firmware
// not stepped for D, its next step D + 1 ms after the last) against the derived rule, one lost period per 68 ms
// (docs/firmware.md, "Timing budget").
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "lever/hil/fault_spec.hpp"
#include "lever/hil/simulation.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

struct Outcome {
  std::optional<double> timing_at_s;  // when the lever first latched TIMING, scenario time
  std::uint32_t overruns = 0;
  double worst_torque_nm = 0.0, worst_velocity_rad_s = 0.0;
  double torque_limit_nm = 0.0;
};

// The wall-tap scenario with `late` ticks at one lever, as lever-hil run --fault would inject them.
Outcome run(const std::vector<std::string>& late, bool at_hsi) {
  SimConfig c;
  c.scenario = ScenarioKind::wall_tap;
  c.duration_s = 4.0;
  for (const auto& spec : late) c.faults.push_back(parse_fault_spec(spec + (at_hsi ? ":hsi" : ":top")));
  Outcome o;
  o.torque_limit_nm = c.top_firmware.torque_limit_nm;
  c.observer = [&](const SimView& v) {
    const auto& lever_latched = at_hsi ? v.hsi.supervisor().latched() : v.top.supervisor().latched();
    if (!o.timing_at_s && protocol::has(lever_latched, protocol::Fault::timing)) o.timing_at_s = v.t;
    for (const auto* t : {&v.hsi.telemetry(), &v.top.telemetry()}) {
      o.worst_torque_nm = std::max(o.worst_torque_nm, std::fabs(t->torque_nm));
      o.worst_velocity_rad_s = std::max(o.worst_velocity_rad_s, std::fabs(t->velocity_rad_s));
    }
  };
  const auto r = run_simulation(c);
  o.overruns = at_hsi ? r.hsi_overruns : r.top_overruns;
  return o;
}

std::vector<std::string> every(double start_s, double period_s, int count, double late_s) {
  std::vector<std::string> specs;
  for (int i = 0; i < count; ++i) {
    char spec[64];
    std::snprintf(spec, sizeof spec, "tick-late@%.3f+%.3f", start_s + i * period_s, late_s);
    specs.emplace_back(spec);
  }
  return specs;
}

}  // namespace

TEST_CASE(
    "timing budget in the HIL: late ticks within one lost period per 68 ms never fault; past it, TIMING at "
    "the step that breaks it",
    "[hil][faults][timing]") {
  for (const bool at_hsi : {false, true}) {
    const char* who = at_hsi ? "HSI" : "TOP";
    struct Case {
      const char* name;
      std::vector<std::string> late;
      std::optional<double> timing_at_s;  // the late step that breaks the budget
      std::uint32_t overruns;
    };
    const std::vector<Case> cases{
        {"one tick late (1 ms lost)", {"tick-late@2+0.001"}, std::nullopt, 1},
        {"two ticks late at once (2 ms lost)", {"tick-late@2+0.002"}, 2.002, 1},
        {"one late, another 30 ms later", {"tick-late@2+0.001", "tick-late@2.03+0.001"}, 2.031, 2},
        {"one late, another 70 ms later", {"tick-late@2+0.001", "tick-late@2.07+0.001"}, std::nullopt, 2},
        {"one late every 70 ms, 20 times", every(1.0, 0.07, 20, 0.001), std::nullopt, 20},
        {"one late every 40 ms: the second breaks it", every(1.0, 0.04, 20, 0.001), 1.041, 2},
        {"4 ms stalls, repeated (the old bound never faulted on them)", every(2.0, 0.1, 5, 0.004), 2.004, 1},
    };
    for (const auto& k : cases) {
      SECTION(std::string(who) + ": " + k.name) {
        const Outcome o = run(k.late, at_hsi);
        if (k.timing_at_s) {
          REQUIRE(o.timing_at_s.has_value());
          // The late step itself latches: it comes D + 1 ms after the one before it.
          CHECK(*o.timing_at_s == Approx(*k.timing_at_s).margin(1.5e-3));
          CHECK(o.overruns >= k.overruns);
        } else {
          CHECK_FALSE(o.timing_at_s.has_value());
          CHECK(o.overruns == k.overruns);
        }
        CHECK(o.worst_torque_nm <= o.torque_limit_nm);
        CHECK(o.worst_velocity_rad_s < 10.0);
      }
    }
  }
}
