// lever-ctl's decisions over heartbeats: when a lever is there, when it refuses for good, when to resend.
#include <catch2/catch.hpp>

#include "pair_command.hpp"

using namespace lever;
using ctl::Outcome;
using ctl::Verb;
using protocol::Fault;
using protocol::HeartbeatMessage;
using protocol::LeverState;

namespace {

HeartbeatMessage heartbeat(LeverState state, bool position_valid, protocol::FaultBits faults = 0) {
  HeartbeatMessage h;
  h.state = state;
  h.position_valid = position_valid;
  h.faults = faults;
  return h;
}

Outcome outcome(Verb verb, const HeartbeatMessage& h) { return ctl::judge(verb, h).outcome; }

}  // namespace

TEST_CASE("lever-ctl: a lever not heard is pending, never done or refused", "[ctl]") {
  for (const Verb verb : {Verb::arm, Verb::disarm, Verb::rearm, Verb::home, Verb::tare, Verb::set_deadband}) {
    const auto j = ctl::judge(verb, std::nullopt);
    CHECK(j.outcome == Outcome::pending);
    CHECK(j.why == "no heartbeat heard");
  }
}

TEST_CASE("lever-ctl arm: done when armed, refused in fault, with a fault latched or unhomed, else resent", "[ctl]") {
  CHECK(outcome(Verb::arm, heartbeat(LeverState::armed, true)) == Outcome::done);
  CHECK(outcome(Verb::arm, heartbeat(LeverState::disarmed, true)) == Outcome::pending);
  CHECK(outcome(Verb::arm, heartbeat(LeverState::homing, false)) == Outcome::pending);
  CHECK(outcome(Verb::arm, heartbeat(LeverState::init, false)) == Outcome::pending);
  CHECK(outcome(Verb::arm, heartbeat(LeverState::disarmed, false)) == Outcome::refused);
  const auto in_fault = ctl::judge(Verb::arm, heartbeat(LeverState::fault, true, protocol::bit(Fault::comms_timeout)));
  CHECK(in_fault.outcome == Outcome::refused);
  CHECK(in_fault.why ==
        "fault, position valid, faults comms_timeout: arm does not clear a latched fault; rearm "
        "does, once its condition is gone");
  const auto latched = ctl::judge(
      Verb::arm,
      heartbeat(LeverState::disarmed, true, protocol::bit(Fault::timing) | protocol::bit(Fault::peer_state)));
  CHECK(latched.outcome == Outcome::refused);
  CHECK_THAT(latched.why, Catch::Contains("faults timing, peer_state"));
}

TEST_CASE("lever-ctl rearm: done when armed, refused once the position is lost, resent while a fault may still hold",
          "[ctl]") {
  CHECK(outcome(Verb::rearm, heartbeat(LeverState::armed, true)) == Outcome::done);
  CHECK(outcome(Verb::rearm, heartbeat(LeverState::fault, true, protocol::bit(Fault::comms_timeout))) ==
        Outcome::pending);
  CHECK(outcome(Verb::rearm, heartbeat(LeverState::disarmed, true)) == Outcome::pending);
  CHECK(outcome(Verb::rearm, heartbeat(LeverState::fault, false, protocol::bit(Fault::encoder))) == Outcome::refused);
  CHECK(outcome(Verb::rearm, heartbeat(LeverState::homing, false)) == Outcome::pending);
}

TEST_CASE("lever-ctl home: done when the position is valid, refused in fault saying whether homing itself gave up",
          "[ctl]") {
  CHECK(outcome(Verb::home, heartbeat(LeverState::disarmed, true)) == Outcome::done);
  CHECK(outcome(Verb::home, heartbeat(LeverState::armed, true)) == Outcome::done);
  CHECK(outcome(Verb::home, heartbeat(LeverState::homing, false)) == Outcome::pending);
  CHECK(outcome(Verb::home, heartbeat(LeverState::disarmed, false)) == Outcome::pending);
  const auto gave_up = ctl::judge(Verb::home, heartbeat(LeverState::fault, false, protocol::bit(Fault::homing)));
  CHECK(gave_up.outcome == Outcome::refused);
  CHECK_THAT(gave_up.why, Catch::Contains("homing gave up"));
  const auto faulted = ctl::judge(Verb::home, heartbeat(LeverState::fault, false, protocol::bit(Fault::encoder)));
  CHECK(faulted.outcome == Outcome::refused);
  CHECK_THAT(faulted.why, Catch::Contains("disarm first"));
}

TEST_CASE("lever-ctl disarm: done when disarmed, whatever stays latched", "[ctl]") {
  CHECK(outcome(Verb::disarm, heartbeat(LeverState::disarmed, false, protocol::bit(Fault::encoder))) == Outcome::done);
  CHECK(outcome(Verb::disarm, heartbeat(LeverState::armed, true)) == Outcome::pending);
  CHECK(outcome(Verb::disarm, heartbeat(LeverState::fault, true, 1)) == Outcome::pending);
}

TEST_CASE("lever-ctl tare goes to a disarmed TOP only, set-deadband to its direction's sender, neither confirmable",
          "[ctl]") {
  CHECK_FALSE(ctl::confirmable(Verb::tare));
  CHECK_FALSE(ctl::confirmable(Verb::set_deadband));
  CHECK(ctl::confirmable(Verb::arm));
  const auto tare = ctl::targets(Verb::tare);
  CHECK((!tare.hsi && tare.top));
  const auto motion = ctl::targets(Verb::set_deadband, protocol::Direction::motion);
  CHECK((motion.hsi && !motion.top));
  const auto force = ctl::targets(Verb::set_deadband, protocol::Direction::force);
  CHECK((!force.hsi && force.top));
  CHECK(outcome(Verb::tare, heartbeat(LeverState::disarmed, true)) == Outcome::done);
  CHECK(outcome(Verb::tare, heartbeat(LeverState::armed, true)) == Outcome::refused);
  CHECK(outcome(Verb::set_deadband, heartbeat(LeverState::armed, true)) == Outcome::done);
}

TEST_CASE("lever-ctl: a resend goes only to the targets still pending", "[ctl]") {
  const ctl::Judgement done{Outcome::done, {}}, pending{Outcome::pending, {}}, refused{Outcome::refused, {}};
  const auto both = ctl::still_pending({true, true}, done, pending);
  CHECK((!both.hsi && both.top));
  const auto none = ctl::still_pending({true, true}, done, refused);
  CHECK((!none.hsi && !none.top));
  const auto top_only = ctl::still_pending({false, true}, pending, pending);
  CHECK((!top_only.hsi && top_only.top));
}

TEST_CASE("lever-ctl fault names: every known bit by its name, unknown bits in hex", "[ctl]") {
  CHECK(ctl::fault_names(0) == "none");
  CHECK(ctl::fault_names(protocol::bit(Fault::comms_timeout) | protocol::bit(Fault::can_bus)) ==
        "comms_timeout, can_bus");
  CHECK(ctl::fault_names(0x8001) == "comms_timeout, unknown bits 0x8000");
}
