#pragma once
// What lever-ctl decides from the levers' heartbeats and settings frames: which levers a command is for, whether
// each one shows the commanded state or settings, refuses it for good (a state or a latched fault the command
// cannot get past), or is still pending (resend). Pure functions over frames, so the decisions are unit-tested
// without a bus or a clock.
#include <cstdint>
#include <optional>
#include <string>

#include "lever/protocol/messages.hpp"

namespace lever::ctl {

enum class Verb : std::uint8_t { tare, home, arm, disarm, rearm, set_deadband };

std::string_view verb_name(Verb verb) noexcept;
protocol::Opcode opcode(Verb verb) noexcept;

// Which levers the command goes to, and whose heartbeat judges it: tare only the TOP (the HSI has no gauge and
// would count the command rejected); set_deadband only the direction's sending end, which owns its parameters.
struct Targets {
  bool hsi = true;
  bool top = true;
};
Targets targets(Verb verb, protocol::Direction direction = protocol::Direction::motion) noexcept;

// Whether the command's outcome shows in the lever's settings frame rather than its heartbeat: set_deadband and
// tare change nothing a heartbeat carries. The heartbeat then says only whether the lever accepts the command now.
bool confirmed_by_settings(Verb verb) noexcept;

// pending: resend; taken: the lever has it and is carrying it out (a tare averaging), so wait without resending.
enum class Outcome : std::uint8_t { pending, taken, done, refused };

struct Judgement {
  Outcome outcome = Outcome::pending;
  std::string why;  // for refused and pending: the lever's state as its heartbeat says it, and what would help
};

// One lever's newest heartbeat (none: not heard yet) judged against the command.
Judgement judge(Verb verb, const std::optional<protocol::HeartbeatMessage>& heartbeat);

// Whether a rolling counter of the settings frame (6 bits) moved on from `before`: ahead by 1 to 31. Ahead by
// more is read as behind (a lever that rebooted counts from 0 again).
bool counter_newer(std::uint8_t before, std::uint8_t now) noexcept;

// The settings frame's values a set_deadband command sets.
bool shows(const protocol::SettingsMessage& settings, const protocol::CommandMessage& command) noexcept;

// A lever whose heartbeat accepts set_deadband or tare, judged by its settings frames: `before` the newest heard
// before the first copy went out, `newest` the newest since. set_deadband is done when the changes counter moved
// on and the values are the commanded ones; tare is taken while the gauge averages and done when the tare counter
// moved on and the average is over.
Judgement judge_settings(Verb verb, const protocol::SettingsMessage& before, const protocol::SettingsMessage& newest,
                         const protocol::CommandMessage& command);

// "force: predictive p 0.1000, floor 0.050 N, filter 30.0 Hz; changes 3, tares 1, taring": a settings frame, read.
std::string describe(const protocol::SettingsMessage& settings, protocol::Role role);

// The levers a resend goes to: the targets still pending (one already there, or refusing, is left alone).
Targets still_pending(const Targets& targets, const Judgement& hsi, const Judgement& top) noexcept;
// "fault, position valid, faults comms_timeout": what the heartbeat says, for a message.
std::string describe(const protocol::HeartbeatMessage& heartbeat);

}  // namespace lever::ctl
