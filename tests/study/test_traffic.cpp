// Fig. 8 from session logs: each direction's data frames in the study's intervals as a share of the 1 kHz rate,
// against the p it ran at, from confirmed intervals of trials that counted only (docs/study.md, "lever-study", Fig. 8).
#include <catch2/catch.hpp>

#include "lever/study/rating.hpp"
#include "lever/study/session_log.hpp"
#include "lever/study/three_ifc.hpp"
#include "lever/study/traffic.hpp"

namespace {

namespace study = lever::study;
using study::Direction;
using study::TrafficKey;

// What the runner writes for an interval both levers confirmed and the bus measured.
void measure(study::IntervalRecord& i, std::int64_t start_us, double seconds, std::uint64_t velocity,
             std::uint64_t force) {
  i.start_bus_us = start_us;
  i.end_bus_us = start_us + static_cast<std::int64_t>(seconds * 1e6);
  i.frames_velocity = velocity;
  i.frames_force = force;
  i.confirmed = {{"hsi", {{"mode", "deadband"}, {"p", i.interval.p_velocity}}},
                 {"top", {{"mode", "deadband"}, {"p", i.interval.p_force}}}};
}

// The first 3IFC trial of a session (p = 2.5 % in its carrier), every interval measured: the plain ones sent
// `plain` frames a direction, the carrier `carried`, each over `seconds`.
study::TrialRecord three_ifc_trial(int attempt, double seconds, std::uint64_t plain, std::uint64_t carried) {
  study::ThreeIfcStaircase s({}, 7);
  s.acknowledge();
  auto r = study::record_of(s.current(), attempt);
  for (std::size_t k = 0; k < r.intervals.size(); ++k) {
    const bool carrier = static_cast<int>(k) + 1 == r.carrier;
    measure(r.intervals[k], 1'000'000 * static_cast<std::int64_t>(k) * 30, seconds, carrier ? carried : plain,
            carrier ? carried / 2 : plain / 2);
  }
  r.answer = r.carrier;
  r.right = true;
  return r;
}

std::vector<double> at(const study::TrafficTable& t, Direction d, double p) {
  const auto it = t.percent().find(TrafficKey{d, p});
  return it == t.percent().end() ? std::vector<double>{} : it->second;
}

}  // namespace

TEST_CASE("traffic: frames over the interval's bus time, as a percent of the 1 kHz samples", "[unit][study]") {
  CHECK(study::traffic_percent(5000, 0, 20'000'000) == Approx(25.0));
  CHECK(study::traffic_percent(20'000, 3'000'000, 23'000'000) == Approx(100.0));
  CHECK(study::traffic_percent(0, 0, 1'000'000) == 0.0);
  // An interval ends with the first frame past its length: its own length, not the nominal one, divides.
  CHECK(study::traffic_percent(5000, 0, 20'012'500) == Approx(100.0 * 5000 / 20012.5));
}

TEST_CASE("traffic: each direction at its own p, the plain intervals at p = 0", "[unit][study]") {
  study::TrafficTable t;
  t.add({three_ifc_trial(2, 20.0, 12'000, 5'000)}, false);
  CHECK(t.tally().counted == 3);
  CHECK_THAT(at(t, Direction::velocity, 0.0), Catch::Matchers::Approx(std::vector<double>{60.0, 60.0}));
  CHECK_THAT(at(t, Direction::force, 0.0), Catch::Matchers::Approx(std::vector<double>{30.0, 30.0}));
  CHECK_THAT(at(t, Direction::velocity, 0.025), Catch::Matchers::Approx(std::vector<double>{25.0}));
  CHECK_THAT(at(t, Direction::force, 0.025), Catch::Matchers::Approx(std::vector<double>{12.5}));
  CHECK(t.percent().size() == 4);
  CHECK_FALSE(t.simulated({Direction::velocity, 0.0}));
}

TEST_CASE("traffic: a rating run's other direction ran at p = 0 and counts there", "[unit][study]") {
  study::RatingRun run({}, 3);
  run.acknowledge();
  run.acknowledge();
  auto r = study::record_of(run.current(), 3);
  REQUIRE(r.direction == Direction::velocity);
  REQUIRE(r.intervals.size() == 1);
  measure(r.intervals[0], 0, 30.0, 9'000, 6'000);
  r.answer = 7;
  study::TrafficTable t;
  t.add({r}, true);
  CHECK_THAT(at(t, Direction::velocity, r.p), Catch::Matchers::Approx(std::vector<double>{30.0}));
  CHECK_THAT(at(t, Direction::force, 0.0), Catch::Matchers::Approx(std::vector<double>{20.0}));
  CHECK(t.simulated({Direction::force, 0.0}));
}

TEST_CASE("traffic: a void trial's intervals are left out, even those measured whole before it was spoilt",
          "[unit][study]") {
  auto spoilt = three_ifc_trial(2, 20.0, 1'000, 1'000);
  spoilt.void_reason = "interval 3: the TOP faulted";
  spoilt.answer.reset();
  spoilt.right.reset();
  study::TrafficTable t;
  t.add({spoilt, three_ifc_trial(3, 20.0, 12'000, 5'000)}, false);
  CHECK(t.tally().void_trial == 3);
  CHECK(t.tally().counted == 3);
  CHECK_THAT(at(t, Direction::velocity, 0.0), Catch::Matchers::Approx(std::vector<double>{60.0, 60.0}));
  CHECK_THAT(at(t, Direction::velocity, 0.025), Catch::Matchers::Approx(std::vector<double>{25.0}));
}

TEST_CASE("traffic: an interval the levers did not confirm, or confirmed at another p, is left out", "[unit][study]") {
  auto r = three_ifc_trial(2, 20.0, 12'000, 5'000);
  const auto carrier = static_cast<std::size_t>(r.carrier - 1);
  const auto plain = carrier == 0 ? 1u : 0u;
  r.intervals[carrier].confirmed = nullptr;         // the runner never saw the settings frames
  r.intervals[plain].confirmed["top"]["p"] = 0.05;  // the TOP ran something else
  study::TrafficTable t;
  t.add({r}, false);
  CHECK(t.tally().unconfirmed == 2);
  CHECK(t.tally().counted == 1);
  CHECK(at(t, Direction::velocity, 0.025).empty());
  CHECK(at(t, Direction::velocity, 0.0).size() == 1);
  // Within half the settings frame's step of p is the p asked for.
  auto rounded = three_ifc_trial(2, 20.0, 12'000, 5'000);
  rounded.intervals[carrier].confirmed["hsi"]["p"] = 0.02504;
  study::TrafficTable u;
  u.add({rounded}, false);
  CHECK(u.tally().counted == 3);
}

TEST_CASE("traffic: intervals without bus times or frames, and the steps that take no answer, add nothing",
          "[unit][study]") {
  study::ThreeIfcStaircase s({}, 7);
  auto familiarization = study::record_of(s.current(), 1);
  measure(familiarization.intervals[0], 0, 45.0, 40'000, 30'000);  // measured, but the subject's own exploring
  s.acknowledge();
  auto simulated = study::record_of(s.current(), 2);  // as simulate-session writes it: the runner's fields null
  simulated.answer = 1;
  auto zero = three_ifc_trial(3, 20.0, 12'000, 5'000);
  zero.intervals[0].end_bus_us = zero.intervals[0].start_bus_us;
  study::TrafficTable t;
  t.add({familiarization, simulated, zero}, false);
  CHECK(t.tally().unmeasured == 4);
  CHECK(t.tally().counted == 2);
  CHECK(at(t, Direction::velocity, 0.0).size() + at(t, Direction::velocity, 0.025).size() == 2);
}

TEST_CASE("traffic: a p that differs in its last bits from session to session is one point", "[unit][study]") {
  auto a = three_ifc_trial(2, 20.0, 12'000, 5'000);
  auto b = three_ifc_trial(2, 20.0, 12'000, 5'000);
  for (auto& i : b.intervals)
    if (i.interval.p_velocity > 0) {
      i.interval.p_velocity = 0.025 + 1e-15;
      i.interval.p_force = 0.025 + 1e-15;
      i.confirmed["hsi"]["p"] = i.interval.p_velocity;
      i.confirmed["top"]["p"] = i.interval.p_force;
    }
  study::TrafficTable t;
  t.add({a}, false);
  t.add({b}, true);
  CHECK(at(t, Direction::velocity, 0.025).size() == 2);
  CHECK(t.percent().size() == 4);
  CHECK(t.simulated({Direction::velocity, 0.025}));
}
