// Quadrature decoding, velocity estimation and the strain gauge.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>

#include "lever/fw/adaptive_window_velocity.hpp"
#include "lever/fw/quadrature_decoder.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/fw/velocity_estimator.hpp"

using namespace lever::fw;

namespace {
// Forward Gray sequence in (A<<1)|B coding: 00, 01, 11, 10.
constexpr AbState kForward[4] = {0b00, 0b01, 0b11, 0b10};
}  // namespace

TEST_CASE("the decoder's transition table: +1 forward, -1 backward, 0 unchanged, illegal when both lines flip",
          "[firmware][encoder]") {
  for (int from = 0; from < 4; ++from) {
    for (int to = 0; to < 4; ++to) {
      QuadratureDecoder d;
      d.reset(static_cast<AbState>(from));
      d.feed(static_cast<AbState>(to));
      int from_index = 0, to_index = 0;
      for (int i = 0; i < 4; ++i) {
        if (kForward[i] == from) from_index = i;
        if (kForward[i] == to) to_index = i;
      }
      const int distance = (to_index - from_index + 4) % 4;
      INFO("from " << from << " to " << to);
      if (distance == 0) {
        CHECK(d.counts() == 0);
        CHECK(d.illegal_transitions() == 0u);
      } else if (distance == 1) {
        CHECK(d.counts() == 1);
      } else if (distance == 3) {
        CHECK(d.counts() == -1);
      } else {
        CHECK(d.counts() == 0);
        CHECK(d.illegal_transitions() == 1u);
      }
    }
  }
}

TEST_CASE("a full revolution counts 4 per line, both ways", "[firmware][encoder]") {
  QuadratureDecoder d;
  d.reset(kForward[0]);
  for (int i = 1; i <= 4096 * 4; ++i) d.feed(kForward[i % 4]);
  CHECK(d.counts() == 16384);
  for (int i = 4096 * 4 - 1; i >= 0; --i) d.feed(kForward[i % 4]);
  CHECK(d.counts() == 0);
  CHECK_FALSE(d.fault());
}

TEST_CASE("illegal transitions latch an encoder fault past the threshold; re-arming restarts the tally",
          "[firmware][encoder]") {
  QuadratureDecoder d({3});
  d.reset(0b00);
  for (int i = 0; i < 3; ++i) {
    d.feed(0b11);
    d.feed(0b00);
  }
  CHECK(d.illegal_transitions() == 6u);
  CHECK(d.fault());
  d.feed(0b01);  // good edges do not clear it
  CHECK(d.fault());
  d.clear_fault();
  CHECK_FALSE(d.fault());
  CHECK(d.counts() == 1);
}

TEST_CASE("lost edges latch the encoder fault at once, and clearing restarts both tallies", "[firmware][encoder]") {
  QuadratureDecoder d({8});
  d.reset(0b00);
  d.feed(0b01);
  CHECK_FALSE(d.fault());
  d.note_lost(0);
  CHECK_FALSE(d.fault());
  d.note_lost(3);
  CHECK(d.fault());  // one gap is enough: the count is off by an unknown amount
  CHECK(d.lost_edges() == 3u);
  d.clear_fault();
  CHECK_FALSE(d.fault());
  CHECK(d.lost_edges() == 0u);
}

TEST_CASE("the index edge marks its count once", "[firmware][encoder]") {
  QuadratureDecoder d;
  d.reset(kForward[0]);
  for (int i = 1; i <= 10; ++i) d.feed(EncoderEdge{kForward[i % 4], i == 7});
  const auto index = d.take_index();
  REQUIRE(index.has_value());
  CHECK(*index == 7);
  CHECK_FALSE(d.take_index().has_value());
}

TEST_CASE("a 16-bit hardware counter is unwrapped across its wrap, both ways", "[firmware][encoder]") {
  CounterUnwrapper u(16);
  CHECK(u.update(65000) == -536);  // power-up value, taken as signed 16 bits
  std::int64_t expected = -536;
  std::uint32_t raw = 65000;
  // 20 turns forward in steps of 3000 counts (wrapping every 65536), then back past zero.
  for (int i = 0; i < 110; ++i) {
    raw = (raw + 3000) & 0xFFFFu;
    expected += 3000;
    REQUIRE(u.update(raw) == expected);
  }
  for (int i = 0; i < 150; ++i) {
    raw = (raw - 2999) & 0xFFFFu;
    expected -= 2999;
    REQUIRE(u.update(raw) == expected);
  }
  CHECK(expected < 0);
  // Bits above the width are ignored, as a 16-bit register read into 32 bits may carry junk.
  CounterUnwrapper v(16);
  v.update(0x10005);
  CHECK(v.update(0x20007) == 7);
}

TEST_CASE("backward difference is exact on a ramp and quantized in counts", "[firmware][velocity]") {
  VelocityEstimator v({VelocityMethod::backward_difference, 0.0});
  v.update(0.0, 1e-3);
  CHECK(v.update(0.002, 1e-3) == Approx(2.0));
  CHECK(v.update(0.005, 1e-3) == Approx(3.0));
}

TEST_CASE("the tracking loop follows a ramp with less noise than the backward difference", "[firmware][velocity]") {
  const double count = 2.0 * std::numbers::pi / 16384.0;
  VelocityEstimator loop({VelocityMethod::tracking_loop, 300.0});
  VelocityEstimator diff({VelocityMethod::backward_difference, 0.0});
  const double speed = 0.7;  // rad/s: 1.8 counts per ms, so the difference jumps between 1 and 2 counts
  double loop_sq = 0, diff_sq = 0;
  int n = 0;
  for (int k = 0; k < 3000; ++k) {
    const double angle = std::floor(speed * k * 1e-3 / count) * count;
    const double a = loop.update(angle, 1e-3);
    const double b = diff.update(angle, 1e-3);
    if (k > 500) {  // after the loop settled
      loop_sq += (a - speed) * (a - speed);
      diff_sq += (b - speed) * (b - speed);
      ++n;
    }
  }
  const double loop_rms = std::sqrt(loop_sq / n), diff_rms = std::sqrt(diff_sq / n);
  CHECK(loop_rms < 0.1);
  CHECK(loop_rms * 3 < diff_rms);
}

TEST_CASE("the rate of the tracking loop's angle estimate answers sooner and passes more quantization",
          "[firmware][velocity]") {
  const double count = 2.0 * std::numbers::pi / 16384.0;
  constexpr double b = 300.0, h = 1e-3;
  SECTION("one count at rest: the integrator moves by b^2 h counts, the rate by b^2 h + 2 b") {
    VelocityEstimator integrator({VelocityMethod::tracking_loop, b}), rate({VelocityMethod::tracking_loop_rate, b});
    integrator.update(0.0, h);
    rate.update(0.0, h);
    CHECK(integrator.update(count, h) == Approx(b * b * h * count));
    CHECK(rate.update(count, h) == Approx((b * b * h + 2.0 * b) * count));
  }
  SECTION("a speed that steps from 0 to 1 rad/s: the rate is nearer it at every tick of the first 10 ms") {
    VelocityEstimator integrator({VelocityMethod::tracking_loop, b}), rate({VelocityMethod::tracking_loop_rate, b});
    integrator.update(0.0, h);
    rate.update(0.0, h);
    for (int k = 1; k <= 10; ++k) {
      const double a = integrator.update(k * h, h), r = rate.update(k * h, h);
      INFO("tick " << k << ": integrator " << a << ", rate " << r);
      CHECK(std::fabs(r - 1.0) < std::fabs(a - 1.0));
    }
  }
  SECTION(
      "on a quantized ramp both settle on the speed; the rate is noisier than the integrator, less than the "
      "difference") {
    VelocityEstimator integrator({VelocityMethod::tracking_loop, b}), rate({VelocityMethod::tracking_loop_rate, b});
    VelocityEstimator diff({VelocityMethod::backward_difference, 0.0});
    const double speed = 0.7;
    double sum = 0.0, integrator_sq = 0.0, rate_sq = 0.0, diff_sq = 0.0;
    int n = 0;
    for (int k = 0; k < 3000; ++k) {
      const double angle = std::floor(speed * k * h / count) * count;
      const double a = integrator.update(angle, h), r = rate.update(angle, h), d = diff.update(angle, h);
      if (k > 500) {
        sum += r;
        integrator_sq += (a - speed) * (a - speed);
        rate_sq += (r - speed) * (r - speed);
        diff_sq += (d - speed) * (d - speed);
        ++n;
      }
    }
    CHECK(sum / n == Approx(speed).margin(0.01));
    CHECK(std::sqrt(rate_sq / n) > 2.0 * std::sqrt(integrator_sq / n));
    CHECK(std::sqrt(rate_sq / n) < std::sqrt(diff_sq / n));
  }
}

TEST_CASE("the tracking loop is stable for every step it is given: late ticks make it lag, never blow up",
          "[firmware][velocity][timing]") {
  const double count = 2.0 * std::numbers::pi / 16384.0;
  // A 20 ms hiccup while moving at 1 rad/s (explicit Euler turned this into 37 rad/s).
  VelocityEstimator v({VelocityMethod::tracking_loop, 300.0});
  double angle = 0.0;
  for (int k = 0; k < 1000; ++k) v.update(std::floor((angle += 1e-3) / count) * count, 1e-3);
  angle += 0.020;
  const double after = v.update(std::floor(angle / count) * count, 0.020);
  CHECK(std::fabs(after - 1.0) < 0.2);
  // Every step the core accepts, sustained (Euler diverged above about 2.8 ms at 300 rad/s): the estimate
  // stays within the true speed's band and converges to it.
  for (const double dt : {1e-3, 2e-3, 2.8e-3, 3e-3, 5e-3, 10e-3, 50e-3}) {
    VelocityEstimator w({VelocityMethod::tracking_loop, 300.0});
    double a = 0.0, worst = 0.0, last = 0.0;
    for (int k = 0; k < 400; ++k) {
      a += 0.5 * dt;
      last = w.update(std::floor(a / count) * count, dt);
      worst = std::max(worst, std::fabs(last));
    }
    INFO("dt " << dt);
    CHECK(worst < 0.5 * 1.3);  // critically damped: a small overshoot, no growth
    CHECK(last == Approx(0.5).margin(0.05));
  }
  // The angle estimate's rate passes the quantization the integrator filters, so it is held to no growth: over the
  // last 100 steps it swings no wider than over the first 100 after its rise, and its mean is the speed.
  for (const double dt : {1e-3, 2e-3, 2.8e-3, 3e-3, 5e-3, 10e-3, 50e-3}) {
    VelocityEstimator w({VelocityMethod::tracking_loop_rate, 300.0});
    double a = 0.0, early = 0.0, late = 0.0, late_sum = 0.0;
    for (int k = 0; k < 400; ++k) {
      a += 0.5 * dt;
      const double error = std::fabs(w.update(std::floor(a / count) * count, dt) - 0.5);
      if (k >= 20 && k < 120) early = std::max(early, error);
      if (k >= 300) {
        late = std::max(late, error);
        late_sum += w.state().rate;
      }
    }
    INFO("dt " << dt);
    CHECK(late <= early + 1e-9);  // the quantization repeats its pattern: equal swings are no growth
    CHECK(late_sum / 100.0 == Approx(0.5).margin(0.05));
  }
}

// The adaptive-window difference (Janabi-Sharifi, Hayward and Chen 2000, end fit, d = 1 count, 20 ms): exactly
// zero at rest, fine steps at a slow constant speed, and a short window as soon as the lever accelerates.
TEST_CASE("the tracking loop's 1 ms step is stable up to its stated limit and rings out past it",
          "[firmware][velocity]") {
  // One count of quantization once, then a still lever: the estimate's swing over ticks 9000-10000 against its
  // first 1000 ticks. Just under the limit the slowest pole (magnitude near 1) still decays; just past it, it grows.
  const auto late_over_early = [](double bandwidth) {
    VelocityEstimator v({VelocityMethod::tracking_loop, bandwidth});
    constexpr double kCount = 2.0 * std::numbers::pi / 16384.0;
    double early = 0.0, late = 0.0;
    for (int k = 0; k < 10000; ++k) {
      const double speed = std::fabs(v.update(k == 0 ? 0.0 : kCount, kSecondsPerTick));
      if (!std::isfinite(speed)) return std::numeric_limits<double>::infinity();  // grown past a double
      if (k > 0 && k <= 1000) early = std::max(early, speed);
      if (k > 9000) late = std::max(late, speed);
    }
    return late / early;
  };
  const double limit = VelocityEstimator::kMaxStableBandwidthRadS;
  CHECK(limit == Approx(828.427).epsilon(1e-5));
  CHECK(late_over_early(0.99 * limit) < 1.0);
  CHECK(late_over_early(1.01 * limit) > 1.0);
}

TEST_CASE("the adaptive window is zero at rest, fine when slow, quick when the speed changes", "[firmware][velocity]") {
  SECTION("at rest every window is flat: exactly zero, over the longest window") {
    AdaptiveWindowVelocity w;
    for (Tick t = 1; t <= 50; ++t) CHECK(w.update(1234, t) == 0.0);
    CHECK(w.window() == 20u);
  }
  SECTION("a quarter count a tick: within 1/20 count of it, where the one-tick difference is 0 or 1") {
    AdaptiveWindowVelocity w;
    double worst = 0.0;
    for (Tick t = 1; t <= 200; ++t) {
      const double v = w.update(static_cast<std::int64_t>(std::floor(0.25 * static_cast<double>(t))), t);
      if (t > 40) worst = std::max(worst, std::fabs(v - 0.25));
    }
    CHECK(worst <= 0.05 + 1e-12);
    CHECK(w.window() >= 16u);
  }
  SECTION("from rest to 2 counts a tick: the window shrinks and follows within 3 ticks") {
    AdaptiveWindowVelocity w;
    std::int64_t count = 0;
    for (Tick t = 1; t <= 30; ++t) w.update(count, t);
    double v = 0.0;
    for (Tick t = 31; t <= 33; ++t) v = w.update(count += 2, t);
    CHECK(v == Approx(2.0).margin(0.35));
    CHECK(w.window() <= 3u);
  }
  SECTION("the window never exceeds its maximum, and late ticks count as time") {
    AdaptiveWindowVelocity w({5, 1});
    for (Tick t = 1; t <= 30; ++t) w.update(7, t);
    CHECK(w.window() == 5u);
    AdaptiveWindowVelocity late;
    late.update(0, 10);
    CHECK(late.update(6, 13) == Approx(2.0));  // 6 counts over 3 ticks
  }
}

TEST_CASE("the strain gauge applies its calibration", "[firmware][gauge]") {
  StrainGauge g({0.01, 100.0, -32768, 32767, 5, 4});
  const auto f = g.update(ForceReading{600, 10, false}, 10);
  REQUIRE(f.has_value());
  CHECK(*f == Approx(5.0));
  CHECK_FALSE(g.state().stale);
  CHECK_FALSE(g.state().saturated);
}

TEST_CASE("a reading older than the staleness window gives no force, not the old number", "[firmware][gauge]") {
  StrainGauge g({0.01, 0.0, -32768, 32767, 5, 4});
  CHECK_FALSE(g.update(std::nullopt, 0).has_value());  // never read
  CHECK(g.state().stale);
  const ForceReading r{100, 10, false};
  CHECK(g.update(r, 10).has_value());
  CHECK(g.update(r, 15).has_value());  // 5 ticks old: still within the window
  CHECK_FALSE(g.update(r, 16).has_value());
  CHECK(g.state().stale);
  CHECK(g.update(ForceReading{100, 16, false}, 16).has_value());  // a fresh sample heals it
}

TEST_CASE("a failed transfer is no sample: neither its value nor its time is taken", "[firmware][gauge]") {
  StrainGauge g({0.01, 0.0, -32768, 32767, 5, 4});
  REQUIRE(g.update(ForceReading{100, 16, false}, 16) == Approx(1.0));
  // A fresh-looking reading that the transport marked failed: the force stays the last good one...
  const auto during = g.update(ForceReading{5000, 17, true}, 17);
  REQUIRE(during.has_value());
  CHECK(*during == Approx(1.0));
  // ...and it does not keep the gauge fresh: 6 ticks after the last good sample it is stale.
  g.update(ForceReading{5000, 21, true}, 21);
  CHECK_FALSE(g.update(ForceReading{5000, 22, true}, 22).has_value());
  CHECK(g.state().stale);
  // Each failure is counted once, by its tick, however many ticks it is the newest thing the source has.
  CHECK(g.state().failed_readings == 3u);
  g.update(ForceReading{5000, 22, true}, 23);
  g.update(ForceReading{5000, 22, true}, 24);
  CHECK(g.state().failed_readings == 3u);
  g.update(ForceReading{100, 25, false}, 25);
  CHECK(g.state().failed_readings == 3u);
  CHECK_FALSE(g.state().stale);
}

TEST_CASE("codes at the ADC's limits are saturated", "[firmware][gauge]") {
  StrainGauge g({0.01, 0.0, -1000, 1000, 5, 4});
  g.update(ForceReading{999, 1, false}, 1);
  CHECK_FALSE(g.state().saturated);
  g.update(ForceReading{1000, 2, false}, 2);
  CHECK(g.state().saturated);
  g.update(ForceReading{-1000, 3, false}, 3);
  CHECK(g.state().saturated);
}

TEST_CASE("tare averages fresh readings only and zeroes the force", "[firmware][gauge]") {
  StrainGauge g({0.01, 0.0, -32768, 32767, 5, 4});
  g.start_tare();
  const double raws[] = {200, 202, 198, 200};
  Tick tick = 1;
  for (const auto raw : raws) {
    g.update(ForceReading{raw, tick, false}, tick);
    g.update(ForceReading{raw, tick, false}, tick + 1);  // the same sample twice: counted once
    tick += 2;
  }
  CHECK_FALSE(g.taring());
  CHECK(g.state().offset_counts == Approx(200.0));
  const auto f = g.update(ForceReading{300, tick, false}, tick);
  REQUIRE(f);
  CHECK(*f == Approx(1.0));
}

TEST_CASE("a reading the source flags saturated is saturated whatever its value", "[firmware][gauge]") {
  StrainGauge g({0.01, 0.0, -1000, 1000, 5, 4});
  g.update(ForceReading{10, 1, false, true}, 1);
  CHECK(g.state().saturated);
  g.update(ForceReading{10, 2, false, false}, 2);
  CHECK_FALSE(g.state().saturated);
}
