// The N-DoF deadzone is a sphere (paper section III-C): decisions do not depend on direction.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>

#include "lever/codec/codec.hpp"
#include "lever/common/rng.hpp"

using lever::Rng;
using lever::Vec;
using namespace lever::codec;

namespace {

using Matrix = std::array<Vec<double, 3>, 3>;

Vec<double, 3> unit(Vec<double, 3> v) {
  const double n = lever::norm(v);
  return {v[0] / n, v[1] / n, v[2] / n};
}

// A random rotation from a random unit quaternion.
Matrix random_rotation(Rng& rng) {
  double q[4];
  double n = 0;
  for (double& c : q) {
    c = rng.normal();
    n += c * c;
  }
  n = std::sqrt(n);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  return {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
           {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
           {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
}

Vec<double, 3> rotate(const Matrix& r, const Vec<double, 3>& v) {
  Vec<double, 3> out{};
  for (int i = 0; i < 3; ++i) out[i] = r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2];
  return out;
}

}  // namespace

TEST_CASE("a direction change is sent exactly when sin(angle) > p (eq. 6-8)", "[codec][isotropy]") {
  Rng rng(7);
  const double p = GENERATE(0.025, 0.1, 0.2);
  for (int trial = 0; trial < 200; ++trial) {
    const auto reference = unit({rng.normal(), rng.normal(), rng.normal()});
    // A second direction orthogonal to the reference.
    auto other = unit({rng.normal(), rng.normal(), rng.normal()});
    const double along = other[0] * reference[0] + other[1] * reference[1] + other[2] * reference[2];
    const auto orthogonal =
        unit({other[0] - along * reference[0], other[1] - along * reference[1], other[2] - along * reference[2]});
    const double magnitude = rng.uniform(0.1, 100.0);
    // At angle a with length cos(a)|v_i| the tip lies at distance sin(a)|v_i| from v_i's tip.
    for (const double scale : {0.999, 1.001}) {
      const double angle = std::asin(p) * scale;
      Vec<double, 3> current{};
      for (int i = 0; i < 3; ++i)
        current[i] = magnitude * std::cos(angle) * (std::cos(angle) * reference[i] + std::sin(angle) * orthogonal[i]);
      DeadbandSender<double, 3> sender({Mode::deadband, p, 0.0, 0.0});
      sender.offer(0.0, {magnitude * reference[0], magnitude * reference[1], magnitude * reference[2]});
      CHECK(sender.offer(0.001, current).send == (scale > 1.0));
    }
  }
}

TEST_CASE("rotating a whole 3-DoF trajectory does not change a single decision", "[codec][isotropy]") {
  Rng rng(11);
  const auto mode = GENERATE(Mode::deadband, Mode::predictive);
  int compared = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const Matrix rotation = random_rotation(rng);
    DeadbandSender<double, 3> plain({mode, 0.1, 0.0, 0.0});
    DeadbandSender<double, 3> rotated({mode, 0.1, 0.0, 0.0});
    Vec<double, 3> x{rng.normal(), rng.normal(), rng.normal()};
    for (int k = 0; k < 400; ++k) {
      const double t = k * 1e-3;
      for (double& c : x) c += 0.05 * rng.normal();
      // Rounding in the rotation could flip a decision that sits within an ulp of the threshold; such a
      // sample would leave the two senders with different histories, so the trial stops there.
      const auto reference = plain.model().at(t);
      const double distance = lever::norm(lever::difference(reference, x));
      const double threshold = 0.1 * lever::norm(reference);
      if (!plain.model().empty() && std::fabs(distance - threshold) < 1e-9 * (1.0 + threshold)) break;
      REQUIRE(plain.offer(t, x).send == rotated.offer(t, rotate(rotation, x)).send);
      ++compared;
    }
  }
  CHECK(compared > 19000);  // nearly all samples were compared
}

TEST_CASE("one isotropic deadzone sends fewer packets than three per-axis deadbands", "[codec][isotropy]") {
  // Paper section III-B: the smallest component triggers per-axis deadbands far more often.
  Rng rng(3);
  DeadbandSender<double, 3> isotropic({Mode::deadband, 0.1, 0.0, 0.0});
  DeadbandSender<double, 1> axis[3] = {DeadbandSender<double, 1>({Mode::deadband, 0.1, 0.0, 0.0}),
                                       DeadbandSender<double, 1>({Mode::deadband, 0.1, 0.0, 0.0}),
                                       DeadbandSender<double, 1>({Mode::deadband, 0.1, 0.0, 0.0})};
  Vec<double, 3> x{1.0, 1.0, 1.0};
  int sent_isotropic = 0, sent_per_axis = 0;
  for (int k = 0; k < 5000; ++k) {
    const double t = k * 1e-3;
    for (double& c : x) c += 0.02 * rng.normal();
    sent_isotropic += isotropic.offer(t, x).send;
    bool any = false;
    for (int i = 0; i < 3; ++i) any = axis[i].offer(t, {x[i]}).send || any;
    sent_per_axis += any;
  }
  CHECK(sent_isotropic * 2 < sent_per_axis);
}
