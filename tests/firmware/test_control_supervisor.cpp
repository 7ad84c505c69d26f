// Control laws and the safety state machine.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "lever/fw/controllers.hpp"
#include "lever/fw/supervisor.hpp"

using namespace lever::fw;

TEST_CASE("PD with velocity feed-forward", "[firmware][control]") {
  PositionController c({10.0, 0.5, 0.02});
  CHECK(c.update(0.1, 2.0, 0.0, 1.0, 1e-3) == Approx(10.0 * 0.1 + 0.5 * 1.0 + 0.02 * 2.0));
  CHECK(c.state().position_error == Approx(0.1));
  CHECK(c.state().velocity_error == Approx(1.0));
}

TEST_CASE("the reference's velocity reaches the D and the feed-forward through its low-pass", "[firmware][control]") {
  PositionController::Config config{10.0, 0.5, 0.02};
  config.reference_velocity_cutoff_hz = 12.5;
  PositionController c(config);
  const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * 12.5 * 1e-3);
  // The first reference passes whole; a step after it moves the filtered one by alpha a tick.
  c.update(0.0, 1.0, 0.0, 0.0, 1e-3);
  CHECK(c.state().velocity_ref == 1.0);
  const double torque = c.update(0.0, 3.0, 0.0, 0.0, 1e-3);
  const double filtered = 1.0 + alpha * 2.0;
  CHECK(c.state().velocity_ref == Approx(filtered).epsilon(1e-12));
  CHECK(torque == Approx((0.5 + 0.02) * filtered).epsilon(1e-12));
  // One count of the HSI's angle in one tick (0.38 rad/s) kicks the TOP by alpha of what it did unfiltered.
  PositionController kicked(config);
  kicked.update(0.0, 0.0, 0.0, 0.0, 1e-3);
  const double count_rad_s = 2.0 * std::numbers::pi / 16384 / 1e-3;
  CHECK(kicked.update(0.0, count_rad_s, 0.0, 0.0, 1e-3) == Approx(alpha * 0.52 * count_rad_s).epsilon(1e-12));
  // After a reset the next reference passes whole again.
  c.reset();
  c.update(0.0, -2.0, 0.0, 0.0, 1e-3);
  CHECK(c.state().velocity_ref == -2.0);
  // A cut-off of 0: as received.
  config.reference_velocity_cutoff_hz = 0.0;
  PositionController raw(config);
  raw.update(0.0, 1.0, 0.0, 0.0, 1e-3);
  CHECK(raw.update(0.0, 3.0, 0.0, 0.0, 1e-3) == Approx(0.52 * 3.0));
}

TEST_CASE("clamp_torque bounds every value, NaN included", "[firmware][control]") {
  CHECK(clamp_torque(5.0, 1.0) == 1.0);
  CHECK(clamp_torque(-5.0, 1.0) == -1.0);
  CHECK(clamp_torque(0.5, 1.0) == 0.5);
  CHECK(clamp_torque(std::nan(""), 1.0) == 0.0);
  CHECK(clamp_torque(INFINITY, 1.0) == 1.0);
}

TEST_CASE("the force display opposes the push, open and closed loop", "[firmware][control]") {
  ForceDisplay open({0.1, 1.0, false, 0.5, 20.0, 5.0, 0.0, 0.1});
  CHECK(open.update(10.0, nullptr, 0.0, 1e-3) == Approx(-1.0));  // 10 N at 0.1 m

  ForceDisplay closed({0.1, 1.0, true, 0.5, 20.0, 5.0, 0.0, 0.1});
  const double own = 8.0;  // the hand feels 2 N too little
  const double first = closed.update(10.0, &own, 0.0, 1e-3);
  CHECK(first == Approx(-(10.0 + 0.5 * 2.0 + 20.0 * 2.0 * 1e-3) * 0.1));
  double torque = first;
  for (int i = 0; i < 10000; ++i) torque = closed.update(10.0, &own, 0.0, 1e-3);
  CHECK(closed.state().integral == Approx(5.0));  // anti-windup
  CHECK(torque == Approx(-(10.0 + 1.0 + 5.0) * 0.1));
}

TEST_CASE("the display damps only in contact", "[firmware][control]") {
  ForceDisplay d({0.1, 1.0, false, 0.5, 20.0, 5.0, 0.3, 0.1});
  CHECK(d.update(0.0, nullptr, 2.0, 1e-3) == 0.0);                       // free space: no drag
  CHECK(d.update(0.05, nullptr, 2.0, 1e-3) == Approx(-0.005));           // below the threshold: none either
  CHECK(d.update(5.0, nullptr, 2.0, 1e-3) == Approx(-0.5 - 0.3 * 2.0));  // in contact: damped wall
}

TEST_CASE("supervisor: init, arm, fault, re-arm", "[firmware][supervisor]") {
  Supervisor s;
  CHECK(s.state() == LeverState::init);
  CHECK_FALSE(s.arm(0));  // not before boot
  s.boot_complete();
  CHECK(s.state() == LeverState::disarmed);
  CHECK_FALSE(s.arm(bit(Fault::force_stale)));  // not while a fault condition holds
  CHECK(s.arm(0));
  CHECK(s.armed());

  s.report(bit(Fault::comms_timeout), 1234);
  CHECK(s.state() == LeverState::fault);
  CHECK(s.fault_since() == 1234);
  CHECK(has(s.latched(), Fault::comms_timeout));
  s.report(0, 1235);  // the condition went away: still latched, still in fault
  CHECK(s.state() == LeverState::fault);
  CHECK_FALSE(s.arm(0));                            // arm does not clear faults; re-arm does
  CHECK_FALSE(s.rearm(bit(Fault::comms_timeout)));  // not while it holds
  CHECK(s.state() == LeverState::fault);
  CHECK(s.rearm(0));
  CHECK(s.armed());
  CHECK(s.latched() == 0);
}

TEST_CASE("supervisor: disarm keeps faults latched; only a re-arm clears them", "[firmware][supervisor]") {
  Supervisor s;
  s.boot_complete();
  REQUIRE(s.arm(0));
  s.report(bit(Fault::encoder), 5);
  CHECK(s.disarm());
  CHECK(s.state() == LeverState::disarmed);
  CHECK(has(s.latched(), Fault::encoder));
  CHECK_FALSE(s.arm(0));
  CHECK(s.rearm(0));
  CHECK(s.latched() == 0);
  CHECK(s.disarm());
  CHECK_FALSE(s.disarm());  // nothing to disarm
}

TEST_CASE("supervisor: homing starts only without torque and without active faults, and a fault ends it",
          "[firmware][supervisor][homing]") {
  Supervisor s;
  CHECK_FALSE(s.home(0));  // not before boot
  s.boot_complete();
  CHECK_FALSE(s.home(bit(Fault::motor_driver)));
  REQUIRE(s.home(0));
  CHECK(s.state() == LeverState::homing);
  CHECK_FALSE(s.arm(0));  // no arming while homing
  s.report(bit(Fault::encoder), 3);
  CHECK(s.state() == LeverState::fault);
  CHECK_FALSE(s.home(0));  // not straight out of fault: the host disarms first
  CHECK(s.state() == LeverState::fault);
  REQUIRE(s.disarm());
  CHECK(s.home(0));  // from disarmed, homing may start again; the latch stays for the re-arm to clear
  CHECK(has(s.latched(), Fault::encoder));
  s.homing_done();
  CHECK(s.state() == LeverState::disarmed);
  CHECK(s.rearm(0));
  CHECK(s.armed());
}
