#pragma once
// What the study runner knows of a pair from its bus: each lever's newest heartbeat and settings frame with their
// kernel receive times, and how many data frames each direction has sent. Fed frames and asked questions, with no
// bus and no clock of its own, so the rules that hold an interval back or void it are unit-tested.
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "lever/protocol/can_frame.hpp"
#include "lever/protocol/messages.hpp"
#include "lever/study/procedure.hpp"

namespace lever::study {

// A lever unheard this long (ten heartbeats, as lever-ctl) is not taken to be in any state.
inline constexpr std::int64_t kHeartbeatFreshUs = 250'000;

struct LeverSeen {
  std::optional<protocol::HeartbeatMessage> heartbeat;
  std::int64_t heartbeat_us = 0;
  std::optional<protocol::SettingsMessage> settings;
  std::int64_t settings_us = 0;
};

// The lever that sends a path's data, and owns its codec settings: velocity the HSI, force the TOP.
constexpr protocol::Role sender_of(protocol::Direction d) noexcept {
  return d == protocol::Direction::motion ? protocol::Role::hsi : protocol::Role::top;
}

// "HSI" or "TOP", as the runner's messages name a lever.
const char* role_name(protocol::Role r) noexcept;

class PairWatch {
 public:
  explicit PairWatch(std::uint8_t pair) noexcept : pair_(pair) {}

  // A frame as read, with its kernel receive time; frames of other pairs or ids, and undecodable ones, are ignored.
  void on_frame(const protocol::CanFrame& frame, std::int64_t t_us) noexcept;

  const LeverSeen& lever(protocol::Role role) const noexcept { return levers_[static_cast<std::size_t>(role)]; }
  std::uint64_t data_frames(protocol::Direction d) const noexcept { return data_[static_cast<std::size_t>(d)]; }
  // The newest receive time of any frame of the pair: the bus's clock as the runner reads it.
  std::int64_t newest_us() const noexcept { return newest_us_; }

  // Why the pair cannot carry an interval at bus time now_us: a lever unheard, not armed, not homed, or with a
  // latched fault. Empty when both can.
  std::string not_ready(std::int64_t now_us) const;

 private:
  std::uint8_t pair_;
  std::array<LeverSeen, 2> levers_{};
  std::array<std::uint64_t, 2> data_{};
  std::int64_t newest_us_ = 0;
};

// The settings one lever is to run for an interval: its settings at the session's start (mode, floor, prefilter)
// with the interval's p on the path it sends.
protocol::SettingsMessage settings_for(const Interval& interval, protocol::Direction d,
                                       const protocol::SettingsMessage& baseline) noexcept;
// The command that asks the path's sending lever for them.
protocol::CommandMessage command_for(protocol::Direction d, const protocol::SettingsMessage& wanted) noexcept;
// Whether a settings frame shows the lever took a command sent when its change counter stood at `changes_before`:
// the counter moved on and the settings are the ones asked for.
bool confirms(const protocol::SettingsMessage& seen, std::uint8_t changes_before,
              const protocol::SettingsMessage& wanted) noexcept;
// What a lever's settings frame showed, received at `at_us`, as an interval's `confirmed` holds it in the log.
nlohmann::json settings_json(const protocol::SettingsMessage& s, std::int64_t at_us);
// "p 5.00 %, floor 0.010, prefilter off, deadband": for the experimenter and the log, never the subject.
std::string describe(const protocol::SettingsMessage& s);

}  // namespace lever::study
