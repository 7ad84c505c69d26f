// The Omni's position sensing (docs/hil-model.md, "The position as the Omni measures it"): the kinematics of its two
// 133.35 mm links invert exactly, and a count of its 15 000-count encoders moves the tip by what the geometry says.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "lever/hil/omni_kinematics.hpp"
#include "lever/hil/sphere3dof.hpp"

using namespace lever;
using namespace lever::hil;

namespace {
const OmniParams kOmni{};
const Vec3 kMiddle{0.01, -0.02, 0.03};
double distance(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
}  // namespace

TEST_CASE("the Omni's kinematics: q = 0 is the workspace's middle, and inverse then forward gives the tip back",
          "[hil][sphere][omni]") {
  const OmniKinematics omni(kMiddle, kOmni.link_m, kOmni.encoder_counts_per_rev);
  CHECK(distance(omni.forward({}), kMiddle) < 1e-15);
  int points = 0;
  // Every point within 40 mm of the middle on each axis: the sphere (25 mm) and the lift off it (up to 15 mm).
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j)
      for (int k = -4; k <= 4; ++k) {
        const Vec3 tip{kMiddle[0] + 0.01 * i, kMiddle[1] + 0.01 * j, kMiddle[2] + 0.01 * k};
        INFO("tip offset " << i << ", " << j << ", " << k << " cm");
        REQUIRE(distance(omni.forward(omni.inverse(tip)), tip) < 1e-12);
        ++points;
      }
  CHECK(points == 9 * 9 * 9);
}

TEST_CASE("the Omni's encoders: one count moves the tip by the link's arc, and the reading is no Cartesian grid",
          "[hil][sphere][omni]") {
  const OmniKinematics omni(kMiddle, kOmni.link_m, kOmni.encoder_counts_per_rev);
  const double count = 2.0 * std::numbers::pi / kOmni.encoder_counts_per_rev;
  const double arc = kOmni.link_m * count;  // 56 um: the data sheet's 450 dpi (55 um)
  CHECK(arc == Approx(55.9e-6).epsilon(0.01));
  const Vec3 at = omni.forward({});
  // At the middle the tip is one link from the yaw axis; the shoulder turns the upper arm alone (the parallelogram
  // keeps the forearm's pitch) and the third encoder the forearm alone: each count moves the tip by one link's arc.
  CHECK(distance(omni.forward({count, 0.0, 0.0}), at) == Approx(arc).epsilon(1e-6));
  CHECK(distance(omni.forward({0.0, count, 0.0}), at) == Approx(arc).epsilon(1e-6));
  CHECK(distance(omni.forward({0.0, 0.0, count}), at) == Approx(arc).epsilon(1e-6));
  // The reading: whole counts, within a count's move of the truth on each axis, and off the 55 um grid.
  int off_grid = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 tip{kMiddle[0] + 1e-4 * i, kMiddle[1] - 7e-5 * i, kMiddle[2] + 3e-5 * i};
    const Vec3 m = omni.measure(tip);
    const OmniJoints q = omni.quantized(omni.inverse(tip));
    for (double a : {q.yaw, q.shoulder, q.forearm}) REQUIRE(std::fabs(a / count - std::round(a / count)) < 1e-6);
    REQUIRE(distance(m, tip) <= 2.0 * arc);
    if (std::fabs(m[0] / kOmni.resolution_m - std::round(m[0] / kOmni.resolution_m)) > 1e-3) ++off_grid;
  }
  CHECK(off_grid > 150);
}
