// The rating procedure's rules (IV-B-3, docs/study.md).
#include <algorithm>
#include <catch2/catch.hpp>

#include "lever/study/rating.hpp"

namespace {

using lever::study::Direction;
using lever::study::Kind;
using lever::study::RatingConfig;
using lever::study::RatingRun;

RatingRun familiarized(std::uint64_t seed = 9) {
  RatingRun r({}, seed);
  r.acknowledge();
  r.acknowledge();
  return r;
}

std::vector<double> presented_order(RatingRun& r) {
  std::vector<double> ps;
  const int run = r.current().pass;
  while (!r.done() && r.current().pass == run) {
    ps.push_back(r.current().p);
    REQUIRE(r.answer(5).accepted);
  }
  return ps;
}

}  // namespace

TEST_CASE("rating: familiarization shows the undistorted system, then the heavily distorted one", "[unit][study]") {
  RatingRun r({}, 1);
  CHECK(r.current().kind == Kind::familiarization);
  CHECK(r.current().p == 0.0);
  CHECK_THROWS_AS(r.answer(5), std::logic_error);
  r.acknowledge();
  CHECK(r.current().kind == Kind::familiarization);
  CHECK(r.current().p == Approx(0.40));
  CHECK(r.current().intervals[0].p_velocity == Approx(0.40));
  CHECK(r.current().intervals[0].p_force == Approx(0.40));
  r.acknowledge();
  CHECK(r.current().kind == Kind::rating);
  CHECK_THROWS_AS(r.acknowledge(), std::logic_error);
}

TEST_CASE("rating: each run presents the twelve values once, in an order drawn from the seed", "[unit][study]") {
  const std::vector<double> paper{0.0, 0.025, 0.05, 0.075, 0.10, 0.125, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40};
  auto r = familiarized();
  for (const auto direction : {Direction::velocity, Direction::force}) {
    CHECK(r.current().direction == direction);
    auto ps = presented_order(r);
    REQUIRE(ps.size() == 12);
    CHECK(ps != paper);  // shuffled (a 1 in 12! chance to fail for a given seed; this one is not it)
    std::sort(ps.begin(), ps.end());
    CHECK(ps == paper);
  }
  CHECK(r.done());
  CHECK(r.ratings().size() == 24);
}

TEST_CASE("rating: the same seed gives the same orders, another seed others; the two runs differ", "[unit][study]") {
  CHECK(RatingRun({}, 4).orders() == RatingRun({}, 4).orders());
  CHECK(RatingRun({}, 4).orders() != RatingRun({}, 5).orders());
  const auto orders = RatingRun({}, 4).orders();
  REQUIRE(orders.size() == 2);
  CHECK(orders[0] != orders[1]);
}

TEST_CASE("rating: every value is equally likely at every position", "[unit][study]") {
  // 12000 orders: the first position's counts against 1000 each; chi-square with 11 degrees of freedom above 31.3
  // has a chance of 1e-3 for a uniform shuffle.
  std::vector<int> first(12, 0);
  const RatingConfig c;
  for (std::uint64_t seed = 0; seed < 12000; ++seed) {
    const auto order = RatingRun(c, seed).orders()[0];
    const auto at = std::find(c.values.begin(), c.values.end(), order[0]) - c.values.begin();
    ++first[static_cast<std::size_t>(at)];
  }
  double chi2 = 0.0;
  for (const int n : first) chi2 += (n - 1000.0) * (n - 1000.0) / 1000.0;
  CHECK(chi2 < 31.3);
}

TEST_CASE("rating: one 30 s interval, p on the run's direction only", "[unit][study]") {
  auto r = familiarized();
  const auto& t = r.current();
  REQUIRE(t.intervals.size() == 1);
  CHECK(t.intervals[0].duration_s == 30.0);
  CHECK(t.intervals[0].p_velocity == t.p);
  CHECK(t.intervals[0].p_force == 0.0);
}

TEST_CASE("rating: every interval of each run carries p on that run's direction only", "[unit][study]") {
  auto r = familiarized();
  for (const auto direction : {Direction::velocity, Direction::force}) {
    for (int i = 0; i < 12; ++i) {
      const auto& t = r.current();
      REQUIRE(t.direction == direction);
      REQUIRE(t.intervals.size() == 1);
      CHECK(t.intervals[0].p_velocity == (direction == Direction::velocity ? t.p : 0.0));
      CHECK(t.intervals[0].p_force == (direction == Direction::force ? t.p : 0.0));
      REQUIRE(r.answer(5).accepted);
    }
  }
  CHECK(r.done());
}

TEST_CASE("rating: a rating is a whole number from 1 to 10; anything else is refused and asked again",
          "[unit][study]") {
  auto r = familiarized();
  const auto before = r.current();
  for (const int bad : {0, 11, -3, 100}) CHECK_FALSE(r.answer(bad).accepted);
  CHECK(r.current().trial == before.trial);
  CHECK(r.ratings().empty());
  CHECK(r.answer(1).accepted);
  CHECK(r.answer(10).accepted);
  REQUIRE(r.ratings().size() == 2);
  CHECK(r.ratings()[0].rating == 1);
  CHECK(r.ratings()[0].p == before.p);
  CHECK(r.ratings()[1].rating == 10);
}

TEST_CASE("rating: a void interval is presented again at the same place in the order", "[unit][study]") {
  auto r = familiarized();
  REQUIRE(r.answer(7).accepted);
  const auto before = r.current();
  r.void_trial();
  CHECK(r.current().trial == before.trial);
  CHECK(r.current().p == before.p);
  CHECK(r.current().direction == before.direction);
  CHECK(r.ratings().size() == 1);
}
