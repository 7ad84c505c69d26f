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

TEST_CASE(
    "lever-ctl tare goes to a disarmed TOP only, set-deadband to its direction's sender, both confirmed by "
    "the settings frame",
    "[ctl]") {
  CHECK(ctl::confirmed_by_settings(Verb::tare));
  CHECK(ctl::confirmed_by_settings(Verb::set_deadband));
  for (const Verb verb : {Verb::arm, Verb::disarm, Verb::rearm, Verb::home})
    CHECK_FALSE(ctl::confirmed_by_settings(verb));
  const auto tare = ctl::targets(Verb::tare);
  CHECK((!tare.hsi && tare.top));
  const auto motion = ctl::targets(Verb::set_deadband, protocol::Direction::motion);
  CHECK((motion.hsi && !motion.top));
  const auto force = ctl::targets(Verb::set_deadband, protocol::Direction::force);
  CHECK((!force.hsi && force.top));
  // What the heartbeat says: whether the lever accepts the command now (the settings frame says the rest).
  CHECK(outcome(Verb::tare, heartbeat(LeverState::disarmed, true)) == Outcome::done);
  CHECK(outcome(Verb::tare, heartbeat(LeverState::armed, true)) == Outcome::refused);
  CHECK(outcome(Verb::set_deadband, heartbeat(LeverState::armed, true)) == Outcome::done);
}

namespace {

protocol::SettingsMessage settings(std::uint8_t changes, std::uint8_t tares = 0, bool taring = false) {
  protocol::SettingsMessage m;
  m.mode = codec::Mode::deadband;
  m.p = 1000;
  m.floor = 50;
  m.filter_hz = 0;
  m.changes = changes;
  m.tares = tares;
  m.taring = taring;
  return m;
}

protocol::CommandMessage set_deadband(codec::Mode mode, std::uint16_t p, std::uint16_t floor, std::uint16_t filter) {
  protocol::CommandMessage c;
  c.opcode = protocol::Opcode::set_deadband;
  c.direction = protocol::Direction::force;
  c.mode = mode;
  c.p = p;
  c.floor = floor;
  c.filter_hz = filter;
  return c;
}

}  // namespace

TEST_CASE("lever-ctl: a settings counter is newer when it moved on by 1 to 31, across the wrap", "[ctl]") {
  CHECK(ctl::counter_newer(3, 4));
  CHECK(ctl::counter_newer(3, 34));
  CHECK_FALSE(ctl::counter_newer(3, 3));
  CHECK_FALSE(ctl::counter_newer(3, 35));  // 32 ahead: as far behind, so not newer
  CHECK_FALSE(ctl::counter_newer(3, 2));
  CHECK(ctl::counter_newer(63, 0));
  CHECK(ctl::counter_newer(62, 1));
  CHECK_FALSE(ctl::counter_newer(0, 63));
}

TEST_CASE("lever-ctl set-deadband: done only when a newer settings frame shows the commanded values", "[ctl]") {
  const auto command = set_deadband(codec::Mode::predictive, 250, 70, 300);
  auto taken = settings(6);
  taken.mode = codec::Mode::predictive;
  taken.p = 250;
  taken.floor = 70;
  taken.filter_hz = 300;
  CHECK(ctl::shows(taken, command));
  CHECK(ctl::judge_settings(Verb::set_deadband, settings(5), taken, command).outcome == Outcome::done);
  // The values already there, but no newer count: the command may not have arrived (a frame from before it).
  auto old = taken;
  old.changes = 5;
  const auto not_arrived = ctl::judge_settings(Verb::set_deadband, settings(5), old, command);
  CHECK(not_arrived.outcome == Outcome::pending);
  CHECK_THAT(not_arrived.why, Catch::Contains("has not arrived"));
  // A newer count with other values: another command came after (or instead of) this one.
  const auto other = ctl::judge_settings(Verb::set_deadband, settings(5), settings(7), command);
  CHECK(other.outcome == Outcome::pending);
  CHECK_THAT(other.why, Catch::Contains("not the commanded ones"));
  // Each value counts: one off is not the commanded setting.
  for (int field = 0; field < 4; ++field) {
    auto off = taken;
    if (field == 0) off.mode = codec::Mode::deadband;
    if (field == 1) off.p = 251;
    if (field == 2) off.floor = 71;
    if (field == 3) off.filter_hz = 0;
    INFO("field " << field);
    CHECK_FALSE(ctl::shows(off, command));
    CHECK(ctl::judge_settings(Verb::set_deadband, settings(5), off, command).outcome == Outcome::pending);
  }
  // Across the counter's wrap.
  auto wrapped = taken;
  wrapped.changes = 0;
  CHECK(ctl::judge_settings(Verb::set_deadband, settings(63), wrapped, command).outcome == Outcome::done);
}

TEST_CASE("lever-ctl tare: taken while the gauge averages (no resend), done once a newer tare has ended", "[ctl]") {
  protocol::CommandMessage tare;
  tare.opcode = protocol::Opcode::tare;
  CHECK(ctl::judge_settings(Verb::tare, settings(0, 2), settings(0, 2), tare).outcome == Outcome::pending);
  CHECK(ctl::judge_settings(Verb::tare, settings(0, 2), settings(0, 2, true), tare).outcome == Outcome::taken);
  CHECK(ctl::judge_settings(Verb::tare, settings(0, 2), settings(0, 3, true), tare).outcome == Outcome::taken);
  CHECK(ctl::judge_settings(Verb::tare, settings(0, 2), settings(0, 3), tare).outcome == Outcome::done);
  CHECK(ctl::judge_settings(Verb::tare, settings(0, 63), settings(0, 0), tare).outcome == Outcome::done);
  // A settings change is no tare.
  CHECK(ctl::judge_settings(Verb::tare, settings(0, 2), settings(1, 2), tare).outcome == Outcome::pending);
  // Taken is not resent.
  const ctl::Judgement taken{Outcome::taken, {}};
  const auto resend = ctl::still_pending({false, true}, taken, taken);
  CHECK((!resend.hsi && !resend.top));
}

TEST_CASE("lever-ctl describes a settings frame in the direction's units", "[ctl]") {
  auto m = settings(3, 1, true);
  m.filter_hz = 300;
  CHECK(ctl::describe(m, protocol::Role::top) ==
        "force: deadband p 0.1000, floor 0.050 N, filter 30.0 Hz; changes 3, tares 1, taring");
  m.filter_hz = 0;
  m.taring = false;
  m.mode = codec::Mode::predictive;
  CHECK(ctl::describe(m, protocol::Role::hsi) ==
        "motion: predictive p 0.1000, floor 0.050 rad/s, filter off; changes 3, tares 1");
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
