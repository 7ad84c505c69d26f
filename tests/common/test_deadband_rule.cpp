// The transmit rule of the paper's eq. (2)/(3) at its edges.
#include <catch2/catch.hpp>
#include <cmath>

#include "lever/codec/codec.hpp"

using lever::Vec;
using namespace lever::codec;

namespace {
Config<double> deadband(double p, double floor = 0.0) { return {Mode::deadband, p, floor, 0.0}; }
}  // namespace

TEST_CASE("the first sample is always sent, even when it is zero", "[codec][rule]") {
  DeadbandSender<double, 1> sender(deadband(0.1));
  CHECK(sender.offer(0.0, {0.0}).send);
  CHECK_FALSE(sender.offer(0.001, {0.0}).send);
}

TEST_CASE("a change equal to the threshold is not sent; the next representable one is", "[codec][rule]") {
  // 1.0 and 0.5 are exact in binary, so the threshold p*|ref| is exactly 0.5.
  DeadbandSender<double, 1> sender(deadband(0.5));
  REQUIRE(sender.offer(0.0, {1.0}).send);
  CHECK_FALSE(sender.offer(0.001, {1.5}).send);
  CHECK_FALSE(sender.offer(0.002, {0.5}).send);
  CHECK(sender.offer(0.003, {std::nextafter(1.5, 2.0)}).send);
}

TEST_CASE("the deadband scales with the reference (Weber's law)", "[codec][rule]") {
  DeadbandSender<double, 1> small(deadband(0.1));
  DeadbandSender<double, 1> large(deadband(0.1));
  small.offer(0.0, {1.0});
  large.offer(0.0, {10.0});
  // The same absolute step of 0.5 is noticeable on 1 N but not on 10 N.
  CHECK(small.offer(0.001, {1.5}).send);
  CHECK_FALSE(large.offer(0.001, {10.5}).send);
}

TEST_CASE("a zero reference sends every change under the paper's rule, and none within the floor", "[codec][rule]") {
  DeadbandSender<double, 1> paper(deadband(0.1));
  paper.offer(0.0, {0.0});
  CHECK_FALSE(paper.offer(0.001, {0.0}).send);
  CHECK(paper.offer(0.002, {1e-300}).send);

  DeadbandSender<double, 1> floored(deadband(0.1, 0.25));
  floored.offer(0.0, {0.0});
  CHECK_FALSE(floored.offer(0.001, {0.25}).send);  // equal to the floor: kept
  CHECK_FALSE(floored.offer(0.002, {-0.25}).send);
  CHECK(floored.offer(0.003, {std::nextafter(0.25, 1.0)}).send);
}

TEST_CASE("the floor only matters where the relative deadband is smaller", "[codec][rule]") {
  DeadbandSender<double, 1> sender(deadband(0.5, 0.25));
  sender.offer(0.0, {4.0});  // relative threshold 2.0 beats the floor
  CHECK_FALSE(sender.offer(0.001, {6.0}).send);
  CHECK(sender.offer(0.002, {std::nextafter(6.0, 7.0)}).send);
}

TEST_CASE("p = 0 sends every change and nothing else", "[codec][rule]") {
  DeadbandSender<double, 1> sender(deadband(0.0));
  sender.offer(0.0, {2.0});
  CHECK_FALSE(sender.offer(0.001, {2.0}).send);
  CHECK(sender.offer(0.002, {std::nextafter(2.0, 3.0)}).send);
}

TEST_CASE("force_send transmits inside the deadband (refresh after silence)", "[codec][rule]") {
  DeadbandSender<double, 1> sender(deadband(0.1));
  sender.offer(0.0, {1.0});
  const auto d = sender.offer(0.001, {1.01}, true);
  CHECK(d.send);
  CHECK(d.value[0] == 1.01);
}

// What the paper counts: the samples its rule sends. A forced send says whether the rule alone would have sent
// it, so a refresh that falls on a noticeable change still counts as the rule's.
TEST_CASE("every decision says whether the rule alone sends the sample, forced or not", "[codec][rule]") {
  DeadbandSender<double, 1> sender(deadband(0.1));
  const auto first = sender.offer(0.0, {1.0});
  CHECK((first.send && first.exceeded));  // no reference yet: the rule sends
  const auto inside = sender.offer(0.001, {1.05});
  CHECK_FALSE((inside.send || inside.exceeded));
  const auto forced_inside = sender.offer(0.002, {1.05}, true);
  CHECK((forced_inside.send && !forced_inside.exceeded));
  const auto forced_outside = sender.offer(0.003, {1.5}, true);
  CHECK((forced_outside.send && forced_outside.exceeded));
  const auto outside = sender.offer(0.004, {2.0});
  CHECK((outside.send && outside.exceeded));
}

TEST_CASE("exceeds_deadzone is the Euclidean rule over all DoF", "[codec][rule]") {
  // |ref| = 5 and p = 0.125 make the threshold exactly 0.625.
  const Vec<double, 3> ref{3.0, 4.0, 0.0};
  CHECK_FALSE(exceeds_deadzone(ref, Vec<double, 3>{3.0, 4.0, 0.625}, 0.125, 0.0));
  CHECK(exceeds_deadzone(ref, Vec<double, 3>{3.0, 4.0, std::nextafter(0.625, 1.0)}, 0.125, 0.0));
  // Every axis moved less than the threshold, but together they left the sphere (|d| = 0.69).
  CHECK(exceeds_deadzone(ref, Vec<double, 3>{3.4, 4.4, 0.4}, 0.125, 0.0));
}
