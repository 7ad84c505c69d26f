#include "pair_command.hpp"

#include <fmt/format.h>

#include "lever/protocol/fault_names.hpp"

namespace lever::ctl {

using protocol::Fault;
using protocol::HeartbeatMessage;
using protocol::LeverState;

std::string_view verb_name(Verb verb) noexcept { return protocol::name(opcode(verb)); }

protocol::Opcode opcode(Verb verb) noexcept {
  switch (verb) {
    case Verb::tare:
      return protocol::Opcode::tare;
    case Verb::home:
      return protocol::Opcode::home;
    case Verb::arm:
      return protocol::Opcode::arm;
    case Verb::disarm:
      return protocol::Opcode::disarm;
    case Verb::rearm:
      return protocol::Opcode::rearm;
    case Verb::set_deadband:
      return protocol::Opcode::set_deadband;
  }
  return protocol::Opcode::disarm;
}

Targets targets(Verb verb, protocol::Direction direction) noexcept {
  if (verb == Verb::tare) return {false, true};
  if (verb == Verb::set_deadband)
    return {direction == protocol::Direction::motion, direction == protocol::Direction::force};
  return {true, true};
}

Targets still_pending(const Targets& t, const Judgement& hsi, const Judgement& top) noexcept {
  return {t.hsi && hsi.outcome == Outcome::pending, t.top && top.outcome == Outcome::pending};
}

bool confirmed_by_settings(Verb verb) noexcept { return verb == Verb::tare || verb == Verb::set_deadband; }

bool counter_newer(std::uint8_t before, std::uint8_t now) noexcept {
  // Unsigned, so that a counter that wrapped (63 -> 0) is 1 ahead, not -63.
  const unsigned ahead = (static_cast<unsigned>(now) - before) % protocol::kSettingsCountModulo;
  return ahead >= 1 && ahead < protocol::kSettingsCountModulo / 2;
}

bool shows(const protocol::SettingsMessage& s, const protocol::CommandMessage& c) noexcept {
  return protocol::same_codec_settings(s, c);
}

std::string describe(const protocol::SettingsMessage& s, protocol::Role role) {
  const bool top = role == protocol::Role::top;
  const auto c = protocol::codec_settings(s);
  const std::string filter = s.filter_hz == 0 ? std::string("off") : fmt::format("{:.1f} Hz", c.filter_hz);
  return fmt::format("{}: {} p {:.4f}, floor {:.3f} {}, filter {}; changes {}, tares {}{}", top ? "force" : "motion",
                     codec::name(c.mode), c.p, c.floor, top ? "N" : "rad/s", filter, s.changes, s.tares,
                     s.taring ? ", taring" : "");
}

Judgement judge_settings(Verb verb, const protocol::SettingsMessage& before, const protocol::SettingsMessage& newest,
                         const protocol::CommandMessage& command) {
  if (verb == Verb::tare) {
    const bool counted = counter_newer(before.tares, newest.tares);
    if (counted && !newest.taring) return {Outcome::done, {}};
    if (newest.taring || counted) return {Outcome::taken, fmt::format("taring (tares {})", newest.tares)};
    return {Outcome::pending, fmt::format("the tare has not arrived: tares {} as before it, not taring", newest.tares)};
  }
  if (!counter_newer(before.changes, newest.changes))
    return {Outcome::pending, fmt::format("the command has not arrived: changes {} as before it", newest.changes)};
  if (!shows(newest, command))
    return {Outcome::pending, fmt::format("changes {} (before it {}), but the values are not the commanded ones: "
                                          "another host's command after it?",
                                          newest.changes, before.changes)};
  return {Outcome::done, {}};
}

std::string describe(const HeartbeatMessage& h) {
  return fmt::format("{}, position {}, faults {}", protocol::name(h.state), h.position_valid ? "valid" : "not valid",
                     protocol::fault_names(h.faults, ", ", "none"));
}

namespace {

Judgement pending(const HeartbeatMessage& h, std::string_view hint) {
  return {Outcome::pending, fmt::format("{} ({})", describe(h), hint)};
}
Judgement refused(const HeartbeatMessage& h, std::string_view why) {
  return {Outcome::refused, fmt::format("{}: {}", describe(h), why)};
}
constexpr Judgement done() { return {Outcome::done, {}}; }

// The rules are the firmware's (firmware/core/include/lever/fw/lever.hpp, on_command; docs/can-protocol.md, "What
// clears a fault"): refused means no resend of this command can get the lever there.
Judgement judge_arm(const HeartbeatMessage& h) {
  switch (h.state) {
    case LeverState::armed:
      return done();
    case LeverState::fault:
      return refused(h, "arm does not clear a latched fault; rearm does, once its condition is gone");
    case LeverState::disarmed:
      if (h.faults != 0) return refused(h, "arm is refused while a fault is latched; rearm clears it");
      if (!h.position_valid) return refused(h, "an unhomed lever does not arm; home it first");
      return pending(h,
                     "the arm has not arrived, or a condition the heartbeat does not show holds: the peer not "
                     "heard, a stale gauge");
    case LeverState::homing:
      return pending(h, "homing: it arms once homed");
    case LeverState::init:
      break;
  }
  return pending(h, "starting");
}

Judgement judge_rearm(const HeartbeatMessage& h) {
  switch (h.state) {
    case LeverState::armed:
      return done();
    case LeverState::fault:
    case LeverState::disarmed:
      if (!h.position_valid) return refused(h, "its position is lost: disarm, home, then rearm");
      return pending(h, "the re-arm has not arrived, or a fault condition still holds");
    case LeverState::homing:
      return pending(h, "homing: it re-arms once homed");
    case LeverState::init:
      break;
  }
  return pending(h, "starting");
}

Judgement judge_disarm(const HeartbeatMessage& h) {
  if (h.state == LeverState::disarmed) return done();
  return pending(h, "the disarm has not arrived");
}

Judgement judge_home(const HeartbeatMessage& h) {
  if (h.position_valid && h.state != LeverState::homing) return done();
  switch (h.state) {
    case LeverState::fault:
      return refused(h, has(h.faults, Fault::homing)
                            ? "homing gave up; disarm, remove what stops it, then home again"
                            : "home is refused in fault; disarm first (the faults stay latched), then home");
    case LeverState::homing:
      return pending(h, "homing");
    case LeverState::disarmed:
      return pending(h,
                     "the home has not arrived, or a fault condition holds: a motor driver fault, a timing "
                     "fault, a bus fault");
    case LeverState::armed:
    case LeverState::init:
      break;
  }
  return pending(h, "starting");
}

// Confirmed by the settings frame (judge_settings): "done" here means the lever is up and accepts the tare now.
Judgement judge_tare(const HeartbeatMessage& h) {
  if (h.state == LeverState::disarmed) return done();
  if (h.state == LeverState::init) return pending(h, "starting");
  return refused(h, "tare is accepted only while disarmed, the lever untouched");
}

}  // namespace

Judgement judge(Verb verb, const std::optional<HeartbeatMessage>& heartbeat) {
  if (!heartbeat) return {Outcome::pending, "no heartbeat heard"};
  const HeartbeatMessage& h = *heartbeat;
  switch (verb) {
    case Verb::arm:
      return judge_arm(h);
    case Verb::rearm:
      return judge_rearm(h);
    case Verb::disarm:
      return judge_disarm(h);
    case Verb::home:
      return judge_home(h);
    case Verb::tare:
      return judge_tare(h);
    case Verb::set_deadband:
      return done();  // accepted in any state by the direction's sending end
  }
  return {Outcome::pending, "unknown command"};
}

}  // namespace lever::ctl
