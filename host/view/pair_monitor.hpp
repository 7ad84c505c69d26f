#pragma once
// What lever-view shows, from the frames on one CAN interface (and the status lines it is given): per pair, each
// lever's heartbeat, the newest data, each direction's frame rate, frames lost or out of order, the bus load and a
// short history. Pure: fed frames with their time stamps, it never touches a socket or a screen, so a recorded
// log gives the figures the live bus gave. Not thread-safe: lever-view's reader thread feeds it under a lock and
// its screen takes a snapshot under the same lock.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "history.hpp"
#include "lever/protocol/can_frame.hpp"
#include "lever/protocol/messages.hpp"
#include "rate_window.hpp"
#include "sequence_counter.hpp"
#include "status_line.hpp"

namespace lever::view {

// The protocol's sample rate: a data stream sending every sample sends 1000 frames a second.
inline constexpr double kSampleRateHz = 1000.0;
// A heartbeat comes every 25 ms (docs/can-protocol.md); four missed in a row and the lever is shown silent.
inline constexpr std::int64_t kSilentAfterUs = 100'000;
// A data stream refreshes at least every 100 ms while its sender is armed; older than two periods, a value is
// shown as stale (its sender stopped: disarmed, faulted, gone).
inline constexpr std::int64_t kStaleAfterUs = 200'000;
// One history sample per 100 ms: 200 of them are the last 20 s.
inline constexpr std::int64_t kHistoryPeriodUs = 100'000;

struct MonitorConfig {
  double bitrate = 1e6;              // bits/s, for the bus load
  std::optional<std::uint8_t> pair;  // show only this pair (the bus load still counts every frame)
};

struct DirectionView {
  std::uint64_t frames = 0;
  std::uint64_t refreshes = 0;  // sent for the refresh period, a rest repeat or a restart: not the deadband's
  std::uint64_t restarts = 0;
  std::uint64_t lost = 0;
  std::uint64_t out_of_order = 0;
  double per_second = 0.0;  // over the last whole second
  double share() const noexcept { return per_second / kSampleRateHz; }
  double savings() const noexcept { return 1.0 - share(); }
};

struct LeverView {
  bool heard = false;                     // a heartbeat since the start
  std::optional<double> heartbeat_age_s;  // since the newest heartbeat
  protocol::HeartbeatMessage heartbeat;   // the newest
  std::uint64_t heartbeats = 0;
  std::uint64_t heartbeats_lost = 0;
  std::uint64_t heartbeats_out_of_order = 0;
  std::uint64_t energy_frames = 0;
  // The newest settings frame: the codec settings of the direction this lever sends (HSI motion, TOP force).
  std::optional<protocol::SettingsMessage> settings;
  std::uint64_t settings_frames = 0;
  std::optional<LeverStatus> status;  // the newest status line of this lever, if any was given
  std::optional<double> status_age_s;
  bool silent() const noexcept { return !heartbeat_age_s || *heartbeat_age_s * 1e6 > kSilentAfterUs; }
};

struct PairView {
  std::uint8_t pair = 0;
  std::array<LeverView, 2> levers{};  // by protocol::Role: HSI, TOP
  DirectionView motion;               // HSI -> TOP
  DirectionView force;                // TOP -> HSI
  // The newest data: the HSI's position and velocity ride on the motion frames, the TOP's force on the force
  // frames. No frame carries the TOP's position, the HSI's own gauge or either motor's torque.
  std::optional<protocol::MotionMessage> motion_message;
  std::optional<double> motion_age_s;
  std::optional<protocol::ForceMessage> force_message;
  std::optional<double> force_age_s;
  std::uint64_t commands = 0;
  std::optional<protocol::Opcode> last_command;
  std::vector<std::optional<float>> hsi_position_history;  // rad, one a kHistoryPeriodUs, oldest first
  std::vector<std::optional<float>> top_force_history;     // N
  std::vector<std::optional<float>> top_position_history;  // rad, from the TOP's status lines

  std::optional<double> hsi_position_rad() const noexcept;
  std::optional<double> hsi_velocity_rad_s() const noexcept;
  std::optional<double> top_force_n() const noexcept;
  bool motion_stale() const noexcept { return !motion_age_s || *motion_age_s * 1e6 > kStaleAfterUs; }
  bool force_stale() const noexcept { return !force_age_s || *force_age_s * 1e6 > kStaleAfterUs; }
};

struct BusView {
  std::uint64_t frames = 0;       // every frame read, any id
  double frames_per_s = 0.0;      // over the last whole second
  double bits_per_s = 0.0;        // with the worst-case stuffing (protocol/can_timing.hpp)
  double load = 0.0;              // bits_per_s over the bit rate
  std::uint64_t unknown_ids = 0;  // frames of no lever message
  std::uint64_t rejected = 0;     // lever ids that failed to decode (DLC, reserved bits, undefined values)
};

struct BridgeView {
  std::size_t source = 0;  // which status input it came from
  BridgeStatus status;
  double age_s = 0.0;
};

struct Snapshot {
  std::int64_t now_us = 0;
  BusView bus;
  std::vector<PairView> pairs;  // the pairs seen, by number
  std::vector<BridgeView> bridges;
  std::uint64_t status_lines = 0;  // status lines read and understood
};

class PairMonitor {
 public:
  explicit PairMonitor(MonitorConfig config = {});

  void on_frame(const protocol::CanFrame& frame, std::int64_t t_us) noexcept;
  void on_status(const StatusLine& line, std::size_t source, std::int64_t t_us);
  // Counters, rates and histories to zero; the newest states and values stay.
  void reset() noexcept;
  // Brings the histories up to now_us and copies out what a screen shows.
  Snapshot snapshot(std::int64_t now_us);

 private:
  struct Direction {
    DirectionView counts;
    SequenceCounter seq;
    RateWindow rate;
  };
  struct Lever {
    bool heard = false;
    std::int64_t heartbeat_us = 0;
    protocol::HeartbeatMessage heartbeat;
    std::uint64_t heartbeats = 0;
    SequenceCounter counter;
    std::uint64_t energy_frames = 0;
    std::optional<protocol::SettingsMessage> settings;
    std::uint64_t settings_frames = 0;
    std::optional<LeverStatus> status;
    std::int64_t status_us = 0;
  };
  struct Pair {
    bool seen = false;
    std::array<Lever, 2> levers{};
    Direction motion, force;
    std::optional<protocol::MotionMessage> motion_message;
    std::int64_t motion_us = 0;
    std::optional<protocol::ForceMessage> force_message;
    std::int64_t force_us = 0;
    std::uint64_t commands = 0;
    std::optional<protocol::Opcode> last_command;
    History hsi_position, top_force, top_position;
  };

  void sample_histories(std::int64_t t_us) noexcept;
  void on_data(Direction& d, const protocol::DataFlags& flags, std::uint8_t seq, std::int64_t t_us) noexcept;
  bool shown(std::uint8_t pair) const noexcept { return !config_.pair || *config_.pair == pair; }

  MonitorConfig config_;
  std::array<Pair, protocol::kPairCount> pairs_{};
  BusView bus_;
  RateWindow bus_frames_, bus_bits_;
  std::vector<std::optional<std::pair<BridgeStatus, std::int64_t>>> bridges_;
  std::uint64_t status_lines_ = 0;
  std::optional<std::int64_t> next_sample_us_;
};

}  // namespace lever::view
