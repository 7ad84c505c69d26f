// The velocity the sphere-3dof's OP reads from its driver (docs/hil-model.md, "The velocity as a device driver gives
// it"): the open-source PHANToM Omni ROS driver's chain, a second-order backward difference and a third-order
// Butterworth low-pass at 20 Hz, and that low-pass designed at any cut-off.
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <numbers>

#include "lever/hil/device_velocity.hpp"
#include "lever/hil/sphere3dof.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

// |H(e^{j 2 pi f / fs})| of the design.
double gain(const Butterworth3& f, double hz, double fs) {
  const std::complex<double> z1 = std::polar(1.0, -2.0 * std::numbers::pi * hz / fs);  // z^-1
  const std::complex<double> num = f.b * (1.0 + 3.0 * z1 + 3.0 * z1 * z1 + z1 * z1 * z1);
  const std::complex<double> den = 1.0 + f.a1 * z1 + f.a2 * z1 * z1 + f.a3 * z1 * z1 * z1;
  return std::abs(num / den);
}

SphereConfig with_chain(SphereVelocityChain chain, double cutoff_hz = 20.0) {
  SphereConfig c;
  c.velocity_chain = chain;
  c.driver_cutoff_hz = cutoff_hz;
  return c;
}

}  // namespace

// The driver prints its coefficients to four digits: (.2196 (u_k + u_(k-3)) + .6588 (u_(k-1) + u_(k-2))) / 1000
// - (-2.7488 y_(k-1) + 2.5282 y_(k-2) - 0.7776 y_(k-3)), "cutoff freq of 20 Hz".
TEST_CASE("the driver's low-pass is the third-order Butterworth at 20 Hz its coefficients print", "[hil][sphere]") {
  const Butterworth3 f = butterworth3(20.0, 1000.0);
  const double half_digit = 0.5e-4 + 1e-12;
  CHECK(std::fabs(1000.0 * f.b - 0.2196) <= half_digit);
  CHECK(std::fabs(3000.0 * f.b - 0.6588) <= half_digit);
  CHECK(std::fabs(f.a1 - -2.7488) <= half_digit);
  CHECK(std::fabs(f.a2 - 2.5282) <= half_digit);
  CHECK(std::fabs(f.a3 - -0.7776) <= half_digit);
  for (const double fc : {10.0, 20.0, 40.0}) {
    CAPTURE(fc);
    const Butterworth3 g = butterworth3(fc, 1000.0);
    CHECK(gain(g, 0.0, 1000.0) == Approx(1.0).epsilon(1e-12));
    CHECK(gain(g, fc, 1000.0) == Approx(1.0 / std::sqrt(2.0)).epsilon(1e-9));  // -3 dB at the cut-off
    CHECK(gain(g, 2.0 * fc, 1000.0) < 0.13);                                   // -18 dB an octave up
  }
}

TEST_CASE("the driver's chain follows a ramp and comes back to rest; the difference moves in whole cells",
          "[hil][sphere]") {
  const Vec3 start{0.01, -0.02, 0.03};
  SECTION("the driver: a ramp's speed after the filter settles, then toward zero, never exactly there") {
    DeviceVelocity v(with_chain(SphereVelocityChain::driver), start);
    Vec3 x = start;
    const Vec3 speed{0.03, -0.01, 0.0};  // m/s
    for (int k = 0; k < 300; ++k) {
      for (std::size_t i = 0; i < 3; ++i) x[i] += speed[i] * 1e-3;
      v.update(x);
    }
    for (std::size_t i = 0; i < 3; ++i) CHECK(v.velocity()[i] == Approx(speed[i]).margin(1e-9));
    for (int k = 0; k < 300; ++k) v.update(x);
    CHECK(std::fabs(v.velocity()[0]) < 1e-3 * speed[0]);
    CHECK(v.velocity()[0] != 0.0);  // an IIR's tail: a wire of 16 bits ends it
  }
  SECTION("held still from the start: exactly zero") {
    DeviceVelocity v(with_chain(SphereVelocityChain::driver), start);
    for (int k = 0; k < 100; ++k) CHECK(v.update(start)[0] == 0.0);
  }
  SECTION("half the cut-off settles slower than twice it") {
    auto settle = [&](double fc) {
      DeviceVelocity v(with_chain(SphereVelocityChain::driver, fc), start);
      Vec3 x = start;
      for (int k = 1;; ++k) {
        x[0] += 0.03e-3;
        if (std::fabs(v.update(x)[0] - 0.03) < 0.003 && k > 5) return k;
      }
    };
    CHECK(settle(10.0) > settle(20.0));
    CHECK(settle(20.0) > settle(40.0));
  }
  SECTION("the difference: one tick of the position, in whole cells of the grid") {
    DeviceVelocity v(with_chain(SphereVelocityChain::difference), start);
    Vec3 x = start;
    x[1] += 55e-6;
    CHECK(v.update(x)[1] == Approx(0.055));
    CHECK(v.update(x)[1] == 0.0);
  }
}

TEST_CASE("sphere-3dof's OP reads its velocity through the configured chain", "[hil][sphere]") {
  for (const double fc : {10.0, 20.0}) {
    CAPTURE(fc);
    SphereConfig c = with_chain(SphereVelocityChain::driver, fc);
    c.duration_s = 3.0;
    c.record_trace = true;
    const auto r = run_sphere(c);
    REQUIRE(r.trace.size() == 3000u);
    DeviceVelocity v(c, r.trace.front().measured);
    int moving = 0;
    for (const auto& row : r.trace) {
      const Vec3& expected = v.update(row.measured);
      for (std::size_t i = 0; i < 3; ++i) REQUIRE(row.velocity[i] == expected[i]);
      moving += row.velocity[0] != 0.0;
    }
    CHECK(moving > 1000);
  }
}
