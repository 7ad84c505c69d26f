// The 3IFC staircase's rules, each as the paper states it (IV-A-2) or as docs/study.md reads it.
#include <array>
#include <catch2/catch.hpp>

#include "lever/study/three_ifc.hpp"

namespace {

using lever::study::Kind;
using lever::study::ThreeIfcConfig;
using lever::study::ThreeIfcStaircase;

int right_answer(const ThreeIfcStaircase& s) { return s.current().carrier; }
int wrong_answer(const ThreeIfcStaircase& s) { return s.current().carrier % 3 + 1; }

void answer_right(ThreeIfcStaircase& s, int times = 1) {
  for (int i = 0; i < times; ++i) REQUIRE(s.answer(right_answer(s)).right == true);
}
void answer_wrong(ThreeIfcStaircase& s, int times = 1) {
  for (int i = 0; i < times; ++i) REQUIRE(s.answer(wrong_answer(s)).right == false);
}

// Past the familiarization, at pass 1's first trial.
ThreeIfcStaircase started(std::uint64_t seed = 7, ThreeIfcConfig c = {}) {
  ThreeIfcStaircase s(c, seed);
  REQUIRE(s.current().kind == Kind::familiarization);
  s.acknowledge();
  return s;
}

// Ends the current pass after `wrongs` wrong answers: p then sits `wrongs` steps above the pass's start.
void end_pass(ThreeIfcStaircase& s, int wrongs) {
  answer_wrong(s, wrongs);
  answer_right(s, 3);
}

}  // namespace

TEST_CASE("3ifc: a session opens with a familiarization at p = 0, then pass 1 starts at p = 2.5 %", "[unit][study]") {
  ThreeIfcStaircase s({}, 1);
  const auto& f = s.current();
  CHECK(f.kind == Kind::familiarization);
  CHECK_FALSE(f.takes_answer());
  REQUIRE(f.intervals.size() == 1);
  CHECK(f.intervals[0].p_velocity == 0.0);
  CHECK(f.intervals[0].p_force == 0.0);
  s.acknowledge();
  const auto& t = s.current();
  CHECK(t.kind == Kind::three_ifc);
  CHECK(t.pass == 1);
  CHECK(t.trial == 1);
  CHECK(t.p == Approx(0.025));
  CHECK(t.answer_min == 1);
  CHECK(t.answer_max == 3);
}

TEST_CASE("3ifc: three 20 s intervals, p on both directions in the carrier only", "[unit][study]") {
  auto s = started();
  const auto& t = s.current();
  REQUIRE(t.intervals.size() == 3);
  for (int i = 1; i <= 3; ++i) {
    const auto& interval = t.intervals[static_cast<std::size_t>(i - 1)];
    CHECK(interval.duration_s == 20.0);
    const double expected = i == t.carrier ? 0.025 : 0.0;
    CHECK(interval.p_velocity == expected);
    CHECK(interval.p_force == expected);
  }
}

TEST_CASE("3ifc: p rises by one step after every wrong answer", "[unit][study]") {
  auto s = started();
  answer_wrong(s);
  CHECK(s.current().p == Approx(0.05));
  answer_wrong(s);
  CHECK(s.current().p == Approx(0.075));
  CHECK(s.current().trial == 3);
}

TEST_CASE("3ifc: p stops rising at 25 %", "[unit][study]") {
  auto s = started();
  answer_wrong(s, 20);
  CHECK(s.current().p == Approx(0.25));
  answer_wrong(s);
  CHECK(s.current().p == Approx(0.25));
  CHECK(s.current().pass == 1);
}

TEST_CASE("3ifc: a right answer keeps p", "[unit][study]") {
  auto s = started();
  answer_wrong(s);
  answer_right(s);
  CHECK(s.current().p == Approx(0.05));
  CHECK(s.right_in_a_row() == 1);
  answer_right(s);
  CHECK(s.current().p == Approx(0.05));
  CHECK(s.right_in_a_row() == 2);
}

TEST_CASE("3ifc: a pass ends at three right answers in a row, not at three right answers", "[unit][study]") {
  auto s = started();
  answer_right(s, 2);
  answer_wrong(s);  // the run starts again, p rises
  answer_right(s, 2);
  CHECK(s.current().kind == Kind::three_ifc);
  CHECK(s.passes().empty());
  answer_right(s);
  REQUIRE(s.passes().size() == 1);
  CHECK(s.passes()[0].p == Approx(0.05));
  CHECK(s.passes()[0].reached);
  CHECK(s.passes()[0].trials == 6);
}

TEST_CASE("3ifc: pass 2 follows a briefing and starts again at 2.5 %", "[unit][study]") {
  auto s = started();
  end_pass(s, 4);  // pass 1 at 12.5 %
  CHECK(s.current().kind == Kind::briefing);
  CHECK_FALSE(s.current().takes_answer());
  CHECK_THROWS_AS(s.answer(1), std::logic_error);
  s.acknowledge();
  CHECK(s.current().kind == Kind::three_ifc);
  CHECK(s.current().pass == 2);
  CHECK(s.current().trial == 1);
  CHECK(s.current().p == Approx(0.025));
}

TEST_CASE("3ifc: pass 3 starts at half of pass 2's result, with no briefing", "[unit][study]") {
  auto s = started();
  end_pass(s, 4);
  s.acknowledge();
  end_pass(s, 5);  // pass 2 at 15 %
  REQUIRE(s.passes().size() == 2);
  CHECK(s.passes()[1].p == Approx(0.15));
  CHECK(s.current().kind == Kind::three_ifc);
  CHECK(s.current().pass == 3);
  CHECK(s.current().p == Approx(0.075));
  answer_wrong(s);
  CHECK(s.current().p == Approx(0.10));
}

TEST_CASE("3ifc: each pass counts its right answers from none: a pass never ends on the last one's run",
          "[unit][study]") {
  auto s = started();
  answer_right(s, 3);  // pass 1 ends on three right in a row
  s.acknowledge();     // the briefing
  answer_right(s);
  CHECK(s.current().pass == 2);
  CHECK(s.right_in_a_row() == 1);
  CHECK(s.passes().size() == 1);
  answer_right(s, 2);  // pass 2 ends; pass 3 follows with no briefing
  REQUIRE(s.passes().size() == 2);
  answer_right(s);
  CHECK(s.current().pass == 3);
  CHECK(s.right_in_a_row() == 1);
  CHECK(s.passes().size() == 2);
}

TEST_CASE("3ifc: the briefing presents the distortion, at the briefing's p on the study's directions",
          "[unit][study]") {
  auto s = started();
  end_pass(s, 1);
  const auto& b = s.current();
  REQUIRE(b.kind == Kind::briefing);
  CHECK(b.p == Approx(0.25));
  REQUIRE(b.intervals.size() == 1);
  CHECK(b.intervals[0].p_velocity == Approx(0.25));
  CHECK(b.intervals[0].p_force == Approx(0.25));
}

TEST_CASE("3ifc: the threshold is the mean of the three passes' results", "[unit][study]") {
  auto s = started();
  end_pass(s, 7);  // 20 %
  CHECK_FALSE(s.threshold());
  s.acknowledge();
  end_pass(s, 4);  // 12.5 %
  CHECK_FALSE(s.threshold());
  end_pass(s, 2);  // 6.25 % + 2 x 2.5 % = 11.25 %
  REQUIRE(s.done());
  REQUIRE(s.passes().size() == 3);
  CHECK(s.passes()[2].p == Approx(0.1125));
  REQUIRE(s.threshold());
  CHECK(*s.threshold() == Approx((0.20 + 0.125 + 0.1125) / 3));
  CHECK(s.reached());
  CHECK_THROWS_AS(s.current(), std::logic_error);
}

TEST_CASE("3ifc: the carrier is drawn from the seed: the same seed, the same carriers", "[unit][study]") {
  const auto carriers = [](std::uint64_t seed) {
    auto s = started(seed);
    std::vector<int> out;
    for (int i = 0; i < 40; ++i) {
      out.push_back(s.current().carrier);
      answer_wrong(s);
    }
    return out;
  };
  CHECK(carriers(11) == carriers(11));
  CHECK(carriers(11) != carriers(12));
}

TEST_CASE("3ifc: each interval carries p a third of the time", "[unit][study]") {
  // 30000 draws: a chi-square with 2 degrees of freedom above 13.8 has a chance of 1e-3 for a uniform draw.
  auto s = started(3);
  std::array<int, 3> counts{};
  constexpr int kDraws = 30000;
  for (int i = 0; i < kDraws; ++i) {
    const int c = s.current().carrier;
    REQUIRE(c >= 1);
    REQUIRE(c <= 3);
    ++counts[static_cast<std::size_t>(c - 1)];
    s.void_trial();
  }
  double chi2 = 0.0;
  for (const int n : counts) chi2 += (n - kDraws / 3.0) * (n - kDraws / 3.0) / (kDraws / 3.0);
  INFO("counts " << counts[0] << " " << counts[1] << " " << counts[2]);
  CHECK(chi2 < 13.8);
}

TEST_CASE("3ifc: a void trial is repeated: same pass, trial and p, the run of right answers kept", "[unit][study]") {
  auto s = started();
  answer_wrong(s);
  answer_right(s, 2);
  const auto before = s.current();
  s.void_trial();
  const auto& after = s.current();
  CHECK(after.kind == before.kind);
  CHECK(after.pass == before.pass);
  CHECK(after.trial == before.trial);
  CHECK(after.p == before.p);
  CHECK(s.right_in_a_row() == 2);
  CHECK(s.passes().empty());
  answer_right(s);  // the third in a row, across the void one
  REQUIRE(s.passes().size() == 1);
  CHECK(s.passes()[0].p == Approx(0.05));
  CHECK(s.passes()[0].trials == 4);
}

TEST_CASE("3ifc: a void trial draws a new carrier: over 300 seeds it moves about two times in three", "[unit][study]") {
  // A carrier kept through the void would move 0 times; a fresh uniform draw 200 +- 8 (binomial sd); below 150 has a
  // chance under 1e-9.
  int moved = 0;
  for (std::uint64_t seed = 0; seed < 300; ++seed) {
    auto s = started(seed);
    const int before = s.current().carrier;
    s.void_trial();
    moved += s.current().carrier != before;
  }
  CHECK(moved > 150);
}

TEST_CASE("3ifc: an answer out of 1..3 is refused and changes nothing", "[unit][study]") {
  auto s = started();
  const auto before = s.current();
  for (const int bad : {0, 4, -1}) {
    const auto outcome = s.answer(bad);
    CHECK_FALSE(outcome.accepted);
    CHECK_FALSE(outcome.refused.empty());
  }
  CHECK(s.current().trial == before.trial);
  CHECK(s.current().carrier == before.carrier);
  CHECK(s.current().p == before.p);
}

TEST_CASE("3ifc: a pass that never stops ends at its trial limit, marked not reached", "[unit][study]") {
  ThreeIfcConfig c;
  c.max_trials_per_pass = 12;
  auto s = started(5, c);
  answer_wrong(s, 12);
  REQUIRE(s.passes().size() == 1);
  CHECK_FALSE(s.passes()[0].reached);
  CHECK(s.passes()[0].p == Approx(0.25));
  CHECK(s.current().kind == Kind::briefing);
}

TEST_CASE("3ifc: directions and interval length come from the config", "[unit][study]") {
  ThreeIfcConfig c;
  c.direction = lever::study::Direction::force;
  c.interval_s = 5.0;
  auto s = started(5, c);
  const auto& t = s.current();
  const auto& carrier = t.intervals[static_cast<std::size_t>(t.carrier - 1)];
  CHECK(carrier.p_velocity == 0.0);
  CHECK(carrier.p_force == Approx(0.025));
  CHECK(carrier.duration_s == 5.0);
  c.start_p = 0.3;
  CHECK_THROWS_AS(ThreeIfcStaircase(c, 1), std::invalid_argument);
}
