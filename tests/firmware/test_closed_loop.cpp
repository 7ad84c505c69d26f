// The whole chain, small: two cores on one in-memory bus with trivial plants. The HSI's motion drives the
// TOP, the TOP meets the wall, and the wall's force comes back to the operator's hand.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

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

// The paper's single PC (lever-hil's one-controller topology): both levers sample and send, then both act, so
// each uses the other's sample of the same tick. With step() one after the other, the HSI would display the TOP's
// force of the tick before.
TEST_CASE("in one controller a sample reaches the other lever in its own tick, both ways", "[firmware][closed-loop]") {
  auto every_change = [](protocol::Role role) {
    fw::LeverConfig c = lever::test::rig_config(role);
    c.motion_codec = {codec::Mode::deadband, 0.0, 0.0, 0.0};
    c.force_codec = {codec::Mode::deadband, 0.0, 0.0, 0.0};
    c.motion_velocity = fw::MotionVelocity::difference;
    return c;
  };
  PairRig rig(every_change(protocol::Role::hsi), every_change(protocol::Role::top));
  rig.one_controller = true;
  rig.boot_and_arm();
  rig.hand_target = 0.4;  // into the wall at 0.3 rad: a force that changes every tick at first
  int compared = 0, pressed = 0, same_force = 0, same_position = 0;
  for (int i = 0; i < 1500; ++i) {
    rig.tick();
    const auto& h = rig.hsi.telemetry();
    const auto& t = rig.top.telemetry();
    if (!h.remote || !t.force_n) continue;
    ++compared;
    pressed += *t.force_n > 1.0;
    same_force += std::fabs(*h.remote - *t.force_n) <= protocol::kForceLsb;
    same_position += std::fabs(t.position_ref_rad - h.position_rad) <= protocol::kPositionLsbRad;
  }
  CHECK(pressed > 100);  // the rig's small contact bounces (docs/firmware.md), so there is force to carry
  CHECK(compared > 1400);
  CHECK(same_force == compared);
  CHECK(same_position == compared);
}

// The paper's velocity (III-E): the quantized position's backward difference. Once the encoder stops counting
// it is exactly zero, so the pure Weber rule (floor 0) sends nothing but refreshes; the smooth estimate still
// decays toward zero after the last count, by more than p of itself, and keeps sending until it rounds to zero
// on the wire.
TEST_CASE("the HSI can send the backward difference: exactly zero at rest, so the paper's rule falls silent",
          "[firmware][closed-loop]") {
  auto deadband_frames_at_rest = [](fw::MotionVelocity velocity) {
    auto hsi = lever::test::rig_config(protocol::Role::hsi);
    hsi.motion_codec = {codec::Mode::deadband, 0.1, 0.0, 0.0};
    hsi.motion_velocity = velocity;
    PairRig rig(hsi);
    rig.boot_and_arm();
    rig.hand_target = 0.15;
    const double rad_per_count = 2.0 * std::numbers::pi / hsi.counts_per_rev;
    bool difference_exact = true;
    for (int i = 0; i < 400; ++i) {
      const auto before = rig.hsi_hal.encoder_.counts;
      rig.tick();
      const double expected = static_cast<double>(rig.hsi_hal.encoder_.counts - before) * rad_per_count / 1e-3;
      difference_exact = difference_exact && std::fabs(rig.hsi.telemetry().velocity_difference_rad_s - expected) < 1e-9;
    }
    CHECK(difference_exact);
    // Back to the middle of a count, until the counts have not changed for 200 ticks. Frames count from the
    // second tick without a new count: the first still carries the step back to zero.
    rig.hand_target = 100.5 * rad_per_count;
    const auto& c = rig.hsi.counters();
    std::uint32_t deadband_before = 0;
    int unchanged = 0;
    bool zero_at_rest = true;
    for (int i = 0; i < 20000 && unchanged < 200; ++i) {
      const auto before = rig.hsi_hal.encoder_.counts;
      rig.tick();
      unchanged = rig.hsi_hal.encoder_.counts == before ? unchanged + 1 : 0;
      if (unchanged == 1) deadband_before = c.data_sent - c.refresh_sent;
      if (unchanged >= 1) zero_at_rest = zero_at_rest && rig.hsi.telemetry().velocity_difference_rad_s == 0.0;
    }
    REQUIRE(unchanged == 200);
    CHECK(zero_at_rest);
    return c.data_sent - c.refresh_sent - deadband_before;
  };
  CHECK(deadband_frames_at_rest(fw::MotionVelocity::difference) == 0u);
  CHECK(deadband_frames_at_rest(fw::MotionVelocity::estimate) > 0u);
}
