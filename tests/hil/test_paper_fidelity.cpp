// Fidelity to the paper, not change detection: each figure the paper's text gives for its two experiments (Fig. 8,
// section IV-A-3; Fig. 12, section IV-B-4) against the HIL's mean over seeds 1-10. The tolerance comes from the
// paper alone: a figure counts as reproduced within 25 % of the paper's own (relative), the smallest effect the
// paper reports as a finding (the linear predictor's 25 % fewer force packets at p = 5 %, IV-B-4), since a model
// further off than that could not show the paper's effects. Where the HIL is further off, the case is an expected
// failure and says so; it fails once the figure is reproduced, and moves over. docs/hil-model.md, "Fidelity to
// the paper", has the table and the reasons. Change detection is test_change_detection.cpp.
#include <catch2/catch.hpp>
#include <cmath>

#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

constexpr double kTolerance = 0.25;  // relative, fixed from the paper before the runs (above)
constexpr int kSeeds = 10;

enum class Figure { velocity_rate, force_rate, contact_share };
enum class Claim { about, at_most };  // "25 %", or "less than 10 %"

// The paper's wall-tap on the lever in the paper's setup (docs/hil-model.md, "The paper's chain, choice by choice"):
// both levers in one controller, the HSI's force loop on, its deadband rule on both directions, no floor, no
// prefilter; counted as the paper counts, the packets the deadband sends; 20 s per seed. The velocity is the
// firmware's one-tick difference unless the adaptive window is asked for.
double lever_rate(double p, Figure figure, fw::MotionVelocity velocity = fw::MotionVelocity::difference) {
  double sum = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SimConfig c;
    c.scenario = ScenarioKind::wall_tap;
    c.duration_s = 20.0;
    c.seed = static_cast<std::uint64_t>(seed);
    c.topology = Topology::one_controller;
    set_hsi_force_loop(c, true);
    c.hsi_firmware.motion_velocity = velocity;
    c.velocity_codec = {codec::Mode::deadband, p, 0.0, 0.0};
    c.force_codec = {codec::Mode::deadband, p, 0.0, 0.0};
    const auto r = run_simulation(c);
    sum += figure == Figure::velocity_rate ? r.velocity_deadband_rate : r.force_deadband_rate;
  }
  return sum / kSeeds;
}

// The 3-DoF sphere: the deadband on one direction, every change sent on the other, as in the paper's runs; the
// paper's 30 s interval per seed.
double sphere_rate(SphereDirection direction, codec::Mode mode, bool filter, double p, Figure figure) {
  double sum = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SphereConfig c = sphere_variant(direction, mode, filter, p);
    c.duration_s = 30.0;
    c.seed = static_cast<std::uint64_t>(seed);
    const auto r = run_sphere(c);
    sum += figure == Figure::velocity_rate ? r.velocity_packet_rate
           : figure == Figure::force_rate  ? r.force_packet_rate
                                           : r.contact_share;
  }
  return sum / kSeeds;
}

void check(double hil, double paper, Claim claim) {
  CAPTURE(hil, paper, kTolerance);
  if (claim == Claim::at_most) {
    CHECK(hil <= paper * (1.0 + kTolerance));
  } else {
    CHECK(std::fabs(hil - paper) <= kTolerance * paper);
  }
}

constexpr auto dz = codec::Mode::deadband;
constexpr auto lp = codec::Mode::predictive;
constexpr auto v = SphereDirection::velocity;
constexpr auto f = SphereDirection::force;

}  // namespace

// Fig. 8: "The traffic volume induced by velocity packets is already at 25% at a deadband size of p=10%".
TEST_CASE("paper fidelity: lever, velocity packets at p = 10 % (paper 25 %)", "[hil][paper-fidelity][!shouldfail]") {
  check(lever_rate(0.10, Figure::velocity_rate), 0.25, Claim::about);
}

// The same with the adaptive-window difference (Janabi-Sharifi, Hayward and Chen 2000), issue 26's variant of the
// lever's velocity: still a time difference of the quantized position, not the default (docs/hil-model.md says why).
TEST_CASE("paper fidelity: lever with the adaptive-window velocity, velocity packets at p = 10 % (paper 25 %)",
          "[hil][paper-fidelity]") {
  check(lever_rate(0.10, Figure::velocity_rate, fw::MotionVelocity::adaptive_window), 0.25, Claim::about);
}

// Fig. 8: "At p=10% only 15% of the original number of packets is transmitted".
TEST_CASE("paper fidelity: lever, force packets at p = 10 % (paper 15 %)", "[hil][paper-fidelity][!shouldfail]") {
  check(lever_rate(0.10, Figure::force_rate), 0.15, Claim::about);
}

// Fig. 8: "Already at p=2.5% the network traffic volume in the backward path is less than 10%".
TEST_CASE("paper fidelity: lever, force packets at p = 2.5 % (paper under 10 %)",
          "[hil][paper-fidelity][!shouldfail]") {
  check(lever_rate(0.025, Figure::force_rate), 0.10, Claim::at_most);
}

// Fig. 12: "during the experiments with 0% deadband the subjects had contact with the environment about 87% of the
// time", inferred from the force packets at p = 0.
TEST_CASE("paper fidelity: sphere, force packets at p = 0 (paper 87 %)", "[hil][paper-fidelity][!shouldfail]") {
  check(sphere_rate(f, dz, false, 0.0, Figure::force_rate), 0.87, Claim::about);
}

TEST_CASE("paper fidelity: sphere, contact share (paper about 87 %)", "[hil][paper-fidelity]") {
  check(sphere_rate(f, dz, false, 0.0, Figure::contact_share), 0.87, Claim::about);
}

// Fig. 12: "Packet rates for velocity packets are reduced by almost 75% when using a barely perceivable 20%
// deadband. For force packets a reduction by almost 90% is possible by chosing the also barely perceivable 5%".
TEST_CASE("paper fidelity: sphere, velocity packets at p = 20 % (paper 25 %)", "[hil][paper-fidelity][!shouldfail]") {
  check(sphere_rate(v, dz, false, 0.20, Figure::velocity_rate), 0.25, Claim::about);
}

TEST_CASE("paper fidelity: sphere, force packets at p = 5 % (paper 10 %)", "[hil][paper-fidelity][!shouldfail]") {
  check(sphere_rate(f, dz, false, 0.05, Figure::force_rate), 0.10, Claim::about);
}

// Fig. 12, linear prediction: "The total savings in comparison to transmission without deadband are 83% and 93%
// for velocity and force packets" (20 % velocity deadband, 5 % force deadband).
TEST_CASE("paper fidelity: sphere, predicted velocity packets at p = 20 % (paper 17 %)",
          "[hil][paper-fidelity][!shouldfail]") {
  check(sphere_rate(v, lp, false, 0.20, Figure::velocity_rate), 0.17, Claim::about);
}

TEST_CASE("paper fidelity: sphere, predicted force packets at p = 5 % (paper 7 %)", "[hil][paper-fidelity]") {
  check(sphere_rate(f, lp, false, 0.05, Figure::force_rate), 0.07, Claim::about);
}

// Fig. 12, prefiltered prediction: "a reduction of packet rate to 8.7% of the original rate for velocity and 7.4%
// for force" (7.5 % and 2.5 %), "a significant improvement (55%) in packet rate at 2.5% deadband in comparison to
// the LP case": the LP case at 2.5 % is then 7.4 % / 0.45 = 16.4 %.
TEST_CASE("paper fidelity: sphere, predicted force packets at p = 2.5 % (paper 16.4 %, derived)",
          "[hil][paper-fidelity]") {
  check(sphere_rate(f, lp, false, 0.025, Figure::force_rate), 0.074 / 0.45, Claim::about);
}

TEST_CASE("paper fidelity: sphere, prefiltered predicted velocity packets at p = 7.5 % (paper 8.7 %)",
          "[hil][paper-fidelity][!shouldfail]") {
  check(sphere_rate(v, lp, true, 0.075, Figure::velocity_rate), 0.087, Claim::about);
}

TEST_CASE("paper fidelity: sphere, prefiltered predicted force packets at p = 2.5 % (paper 7.4 %)",
          "[hil][paper-fidelity][!shouldfail]") {
  check(sphere_rate(f, lp, true, 0.025, Figure::force_rate), 0.074, Claim::about);
}
