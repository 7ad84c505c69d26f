// Linear predictor (paper section III-D) and low-pass prefilter (section III-E).
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "lever/codec/codec.hpp"

using lever::Vec;
using namespace lever::codec;

TEST_CASE("the predictor follows the slope of the last two transmitted samples", "[codec][predictor]") {
  ReferenceModel<double, 1> model(Mode::predictive);
  model.accept(0.010, {2.0});
  CHECK(model.at(0.020)[0] == 2.0);  // one sample: hold it
  model.accept(0.012, {3.0});        // slope 500 per second
  CHECK(model.at(0.012)[0] == 3.0);
  CHECK(model.at(0.016)[0] == Approx(5.0).epsilon(1e-12));
  model.accept(0.013, {3.0});  // flat again
  CHECK(model.at(0.050)[0] == 3.0);
}

TEST_CASE("deadband mode holds the last transmitted value", "[codec][predictor]") {
  ReferenceModel<double, 1> model(Mode::deadband);
  model.accept(0.0, {1.0});
  model.accept(0.001, {2.0});
  CHECK(model.at(0.5)[0] == 2.0);
}

TEST_CASE("a ramp costs two packets in predictive mode and many in deadband mode", "[codec][predictor]") {
  DeadbandSender<double, 1> predictive({Mode::predictive, 0.01, 0.0, 0.0});
  DeadbandSender<double, 1> zoh({Mode::deadband, 0.01, 0.0, 0.0});
  DeadbandReceiver<double, 1> receiver(Mode::predictive);
  int sent_predictive = 0, sent_zoh = 0;
  for (int k = 0; k < 1000; ++k) {
    const double t = k * 1e-3;
    const Vec<double, 1> x{1.0 + 2.0 * t};
    const auto d = predictive.offer(t, x);
    if (d.send) receiver.receive(t, d.wire);
    sent_predictive += d.send;
    sent_zoh += zoh.offer(t, x).send;
    // What the receiver shows is never noticeably off: within the deadband of its own reference.
    const double shown = (*receiver.reconstruct(t))[0];
    CHECK(std::fabs(shown - x[0]) <= 0.01 * std::fabs(shown));
  }
  // The second packet still sees a zero-order hold (one sample known); from the third on the slope is known.
  CHECK(sent_predictive <= 3);
  CHECK(sent_zoh > 50);
}

TEST_CASE("the prefilter's step response is 1 - (1 - alpha)^k", "[codec][filter]") {
  const double cutoff = 10.0, dt = 1e-3;
  const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * cutoff * dt);
  LowPassPrefilter<double, 1> filter(cutoff);
  CHECK(filter.apply(0.0, {0.0})[0] == 0.0);  // y_0 = x_0
  for (int k = 1; k <= 200; ++k) {
    const double y = filter.apply(k * dt, {1.0})[0];
    CHECK(y == Approx(1.0 - std::pow(1.0 - alpha, k)).epsilon(1e-12));
  }
}

TEST_CASE("after one time constant the prefilter reached 63 % of a step", "[codec][filter]") {
  const double cutoff = 5.0, dt = 1e-4;
  const int steps_per_tau = static_cast<int>(std::lround(1.0 / (2.0 * std::numbers::pi * cutoff) / dt));
  LowPassPrefilter<double, 1> filter(cutoff);
  filter.apply(0.0, {0.0});
  double y = 0.0;
  for (int k = 1; k <= steps_per_tau; ++k) y = filter.apply(k * dt, {1.0})[0];
  CHECK(y == Approx(1.0 - std::exp(-1.0)).margin(2e-3));
}

TEST_CASE("the prefilter uses each sample's own interval", "[codec][filter]") {
  const double cutoff = 20.0;
  LowPassPrefilter<double, 1> filter(cutoff);
  filter.apply(0.0, {0.0});
  const double y1 = filter.apply(0.001, {1.0})[0];
  const double y2 = filter.apply(0.004, {1.0})[0];  // a 3 ms gap
  const double a1 = 1.0 - std::exp(-2.0 * std::numbers::pi * cutoff * 0.001);
  const double a3 = 1.0 - std::exp(-2.0 * std::numbers::pi * cutoff * 0.003);
  CHECK(y1 == Approx(a1).epsilon(1e-12));
  CHECK(y2 == Approx(y1 + a3 * (1.0 - y1)).epsilon(1e-12));
}

TEST_CASE("with the prefilter on, transmitted values are the filtered ones", "[codec][filter]") {
  DeadbandSender<double, 1> sender({Mode::deadband, 0.0, 0.0, 10.0});
  LowPassPrefilter<double, 1> reference_filter(10.0);
  for (int k = 0; k < 50; ++k) {
    const double t = k * 1e-3;
    const Vec<double, 1> x{k % 2 ? 1.0 : -1.0};
    const auto filtered = reference_filter.apply(t, x);
    const auto d = sender.offer(t, x);
    if (d.send) CHECK(d.value[0] == filtered[0]);
  }
}

TEST_CASE("config validation rejects what the rule cannot mean", "[codec]") {
  CHECK(is_valid(Config<double>{}));
  CHECK_FALSE(is_valid(Config<double>{Mode::deadband, -0.1, 0.0, 0.0}));
  CHECK_FALSE(is_valid(Config<double>{Mode::deadband, 0.1, -1.0, 0.0}));
  CHECK_FALSE(is_valid(Config<double>{Mode::deadband, 0.1, 0.0, -5.0}));
  CHECK_FALSE(is_valid(Config<double>{Mode::deadband, std::nan(""), 0.0, 0.0}));
  CHECK_FALSE(is_valid(Config<double>{static_cast<Mode>(7), 0.1, 0.0, 0.0}));
  // What a loop at 1 kHz runs: a Weber fraction below 1, a cut-off below 500 Hz; and nothing is_valid refuses.
  CHECK(runs_at(Config<double>{Mode::deadband, 0.9999, 0.0, 499.9}, 1000.0));
  CHECK_FALSE(runs_at(Config<double>{Mode::deadband, 1.0, 0.0, 0.0}, 1000.0));
  CHECK_FALSE(runs_at(Config<double>{Mode::deadband, 0.1, 0.0, 500.0}, 1000.0));
  CHECK(runs_at(Config<double>{Mode::deadband, 0.1, 0.0, 500.0}, 2000.0));
  CHECK_FALSE(runs_at(Config<double>{Mode::deadband, -0.1, 0.0, 0.0}, 1000.0));
  CHECK_FALSE(runs_at(Config<float>{Mode::deadband, 0.1f, 0.0f, std::nanf("")}, 1000.0));
}
