// The simulated observers' models (docs/study.md, "Simulated observers").
#include <catch2/catch.hpp>

#include "lever/study/observer.hpp"

namespace study = lever::study;

TEST_CASE(
    "observer: the Weibull observer guesses at p = 0, lapses at large p, and is 1-1/e of the way at its threshold",
    "[unit][study]") {
  const study::WeibullObserver o{0.10, 3.0, 0.02};
  CHECK(o.p_right(0.0) == Approx(1.0 / 3.0));
  CHECK(o.p_right(10.0) == Approx(0.98));
  CHECK(o.p_right(0.10) == Approx(1.0 / 3.0 + (1.0 - 1.0 / 3.0 - 0.02) * (1.0 - std::exp(-1.0))));
  CHECK(o.p_right(0.05) < o.p_right(0.10));
}

TEST_CASE("observer: the rating observer's mean is 10 at p = 0 and 7 at the paper's anchors", "[unit][study]") {
  const study::RatingObserver o;
  CHECK(o.mean(study::Direction::velocity, 0.0) == Approx(10.0));
  CHECK(o.mean(study::Direction::velocity, 0.20) == Approx(7.0));
  CHECK(o.mean(study::Direction::force, 0.05) == Approx(7.0));
}

TEST_CASE("observer: a simulated session is the same for the same seed", "[unit][study]") {
  const study::WeibullObserver o{0.12, 3.0, 0.02};
  const auto a = study::simulate_three_ifc({}, o, 99);
  const auto b = study::simulate_three_ifc({}, o, 99);
  REQUIRE(a.passes.size() == 3);
  CHECK(a.trials == b.trials);
  CHECK(a.threshold == b.threshold);
}

TEST_CASE("observer: quartiles by linear interpolation", "[unit][study]") {
  const auto s = study::spread_of({4.0, 1.0, 3.0, 2.0, 5.0});
  CHECK(s.median == 3.0);
  CHECK(s.q1 == 2.0);
  CHECK(s.q3 == 4.0);
  CHECK(s.mean == 3.0);
  CHECK(s.sd == Approx(std::sqrt(2.5)));
}
