// The whole chain, small: two cores on one in-memory bus with trivial plants. The HSI's motion drives the
// TOP, the TOP meets the wall, and the wall's force comes back to the operator's hand.
#include <catch2/catch.hpp>
#include <cmath>

#include "lever_rig.hpp"

using namespace lever;
using lever::test::PairRig;

TEST_CASE("the TOP follows the HSI and the wall force comes back", "[firmware][closed-loop]") {
  PairRig rig;
  rig.boot_and_arm();
  const auto hsi_sent_before = rig.hsi.counters().data_sent;
  const auto top_sent_before = rig.top.counters().data_sent;

  // Free motion: the operator moves to 0.2 rad, short of the wall at 0.3 rad.
  rig.hand_target = 0.2;
  double worst_tracking = 0.0;
  for (int i = 0; i < 1500; ++i) {
    rig.tick();
    if (i > 500) worst_tracking = std::max(worst_tracking, std::fabs(rig.top_plant.angle - rig.hsi_plant.angle));
  }
  CHECK(rig.hsi_plant.angle == Approx(0.2).margin(0.01));
  CHECK(worst_tracking < 0.01);
  CHECK(rig.contact_force() == 0.0);

  // Press: the operator aims 0.1 rad past the wall. The contact settles into a small limit cycle driven by
  // the deadbands (docs/firmware.md), so forces are compared as averages over the last second.
  rig.hand_target = 0.4;
  rig.run(1000);
  double wall_sum = 0, displayed_sum = 0, torque_sum = 0, worst_penetration = 0;
  for (int i = 0; i < 1000; ++i) {
    rig.tick();
    wall_sum += rig.contact_force();
    displayed_sum += rig.hsi.telemetry().remote.value_or(0.0);
    torque_sum += rig.hsi_hal.motor_.last.torque_nm;
    worst_penetration = std::max(worst_penetration, rig.hsi_plant.angle - rig.wall_angle);
  }
  const double wall_force = wall_sum / 1000;
  CHECK(rig.top.supervisor().armed());
  CHECK(rig.hsi.supervisor().armed());
  CHECK(wall_force == Approx(3.0).epsilon(0.2));  // the hand's 0.3 N m at 0.1 m, passed through
  CHECK(worst_penetration < 0.03);                // the operator is stopped near the wall
  CHECK(displayed_sum / 1000 == Approx(wall_force).epsilon(0.1));
  CHECK(torque_sum / 1000 == Approx(-wall_force * rig.arm).epsilon(0.1));

  // And the deadband did its job: far fewer frames than samples in both directions.
  const double samples = 3500;  // 1500 free + 2000 pressing
  CHECK((rig.hsi.counters().data_sent - hsi_sent_before) / samples < 0.5);
  CHECK((rig.top.counters().data_sent - top_sent_before) / samples < 0.5);
}
