#pragma once
// What lever-ctl decides from the levers' heartbeats: which levers a command is for, whether each one shows the
// commanded state, refuses it for good (a state or a latched fault the command cannot get past), or is still
// pending (resend). Pure functions over heartbeats, so the decisions are unit-tested without a bus or a clock.
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

// Whether the heartbeat can show the command's outcome. Tare and set_deadband change nothing the heartbeat
// carries: lever-ctl then checks only that the lever is up and in a state that accepts the command, sends it
// a few times (both are idempotent while the first copy's effect lasts) and says the outcome is unconfirmed.
bool confirmable(Verb verb) noexcept;

enum class Outcome : std::uint8_t { pending, done, refused };

struct Judgement {
  Outcome outcome = Outcome::pending;
  std::string why;  // for refused and pending: the lever's state as its heartbeat says it, and what would help
};

// One lever's newest heartbeat (none: not heard yet) judged against the command.
Judgement judge(Verb verb, const std::optional<protocol::HeartbeatMessage>& heartbeat);

// The levers a resend goes to: the targets still pending (one already there, or refusing, is left alone).
Targets still_pending(const Targets& targets, const Judgement& hsi, const Judgement& top) noexcept;

// "comms_timeout, peer_state" (or "none").
std::string fault_names(protocol::FaultBits faults);
// "fault, position valid, faults comms_timeout": what the heartbeat says, for a message.
std::string describe(const protocol::HeartbeatMessage& heartbeat);

}  // namespace lever::ctl
