// The example traces: deterministic per seed and physically plausible.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "trace_generator.hpp"

using namespace lever::tool;

TEST_CASE("the same seed gives the same trace, another seed another", "[tool][generator]") {
  const auto kind = GENERATE(TraceKind::velocity, TraceKind::force, TraceKind::force3);
  const auto a = format_trace_csv(generate_trace({kind, 42, 2.0}));
  CHECK(a == format_trace_csv(generate_trace({kind, 42, 2.0})));
  CHECK(a != format_trace_csv(generate_trace({kind, 43, 2.0})));
}

TEST_CASE("velocity comes from a 16384-count encoder differenced at 1 kHz", "[tool][generator]") {
  const auto trace = generate_trace({TraceKind::velocity, 1, 5.0});
  REQUIRE(trace.samples() == 5000);
  const double count_speed = 2.0 * std::numbers::pi / 16384.0 / 1e-3;
  int moving = 0;
  for (std::size_t i = 0; i < trace.samples(); ++i) {
    const double counts = trace.row(i)[0] / count_speed;
    CHECK(std::fabs(counts - std::round(counts)) < 1e-9);
    moving += counts != 0.0;
    CHECK(std::fabs(trace.row(i)[0]) < 20.0);  // a hand on a lever, not a motor spinning free
  }
  CHECK(moving > 500);
}

TEST_CASE("the force trace alternates contact and free space with gauge noise", "[tool][generator]") {
  const auto trace = generate_trace({TraceKind::force, 1, 10.0});
  int contact = 0, free_space = 0;
  double peak = 0.0;
  for (std::size_t i = 0; i < trace.samples(); ++i) {
    const double f = trace.row(i)[0];
    peak = std::max(peak, f);
    if (f > 0.2) ++contact;
    if (std::fabs(f) < 0.05) ++free_space;
  }
  CHECK(contact > 1000);
  CHECK(free_space > 1000);
  CHECK(peak > 1.0);
  CHECK(peak < 50.0);
}

TEST_CASE("the sphere force is zero outside and points outward inside", "[tool][generator]") {
  const auto trace = generate_trace({TraceKind::force3, 2, 10.0});
  REQUIRE(trace.dof == 3);
  int zero = 0;
  for (std::size_t i = 0; i < trace.samples(); ++i) {
    const double* f = trace.row(i);
    if (f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0) ++zero;
    CHECK(std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) < 0.05 * 300.0);
  }
  // Mostly in contact, as in the paper's experiment (87 %), but not always.
  CHECK(zero > 100);
  CHECK(zero < 5000);
}
