#pragma once
// The lever CAN message set (classic CAN 2.0A, 1 Mbit/s). The single written spec is
// common/protocol/lever.dbc with docs/can-protocol.md; tests/common/test_protocol_dbc.cpp proves these packers
// agree with the DBC bit for bit.
//
// Identifiers carry the lever pair (0..15) in their low bits so that several pairs share one bus; lower ids win
// arbitration, so commands outrank data, data outranks settings and settings outrank heartbeats.
#include <cstdint>
#include <numbers>
#include <string_view>
#include <type_traits>

#include "lever/codec/config.hpp"
#include "lever/protocol/bit_field.hpp"
#include "lever/protocol/can_frame.hpp"
#include "lever/protocol/faults.hpp"

namespace lever::protocol {

enum class Role : std::uint8_t { hsi = 0, top = 1 };

constexpr std::uint8_t kPairCount = 16;
constexpr std::uint32_t kCommandBase = 0x080;    // 0x080 + pair
constexpr std::uint32_t kMotionBase = 0x100;     // 0x100 + pair, HSI -> TOP
constexpr std::uint32_t kForceBase = 0x110;      // 0x110 + pair, TOP -> HSI
constexpr std::uint32_t kEnergyBase = 0x120;     // 0x120 + 2 * pair + role: a data sender's port energy
constexpr std::uint32_t kSettingsBase = 0x140;   // 0x140 + 2 * pair + role: the settings of the direction it sends
constexpr std::uint32_t kHeartbeatBase = 0x700;  // 0x700 + 2 * pair + role

// Stable numbers: they are counted and reported.
enum class DecodeError : std::uint8_t {
  none = 0,
  unknown_id = 1,    // not a lever protocol id
  wrong_dlc = 2,     // payload length differs from the message's
  out_of_range = 3,  // an enumeration or reserved field holds a value the protocol does not define
};

enum class MessageKind : std::uint8_t { command, motion, force, energy, settings, heartbeat };

// The message set, a row a message: its block of identifiers (one per pair, or one per pair and sender), its names
// in common/protocol/lever.dbc, and whether a lever's board hears it. The identifiers, classify(), the board's CAN
// filters (board::lever_pair_filters), the bridge's default allow list and the tools' message names are all read
// from here; tests/common/test_protocol_dbc.cpp holds it to the DBC.
struct MessageSpec {
  MessageKind kind;
  std::uint32_t base;
  bool per_sender;                  // base + 2 * pair + role; otherwise base + pair
  Role sender;                      // who sends it when it is not per sender (a command: a host, addressed as the HSI)
  std::string_view name, top_name;  // the DBC's message names: the HSI's (or the only one) and the TOP's
  // A lever's board passes it. The energy frames do: the passivity observer adds what its peer's port passed on.
  // The settings frames do not: they are for hosts, and a lever follows its peer's settings by the mode on every
  // data frame.
  bool lever_hears;
};
inline constexpr MessageSpec kMessageSet[] = {
    {MessageKind::command, kCommandBase, false, Role::hsi, "LeverCommand", "", true},
    {MessageKind::motion, kMotionBase, false, Role::hsi, "LeverMotion", "", true},
    {MessageKind::force, kForceBase, false, Role::top, "LeverForce", "", true},
    {MessageKind::energy, kEnergyBase, true, Role::hsi, "LeverEnergyHsi", "LeverEnergyTop", true},
    {MessageKind::settings, kSettingsBase, true, Role::hsi, "LeverSettingsHsi", "LeverSettingsTop", false},
    {MessageKind::heartbeat, kHeartbeatBase, true, Role::hsi, "LeverHeartbeatHsi", "LeverHeartbeatTop", true},
};

constexpr const MessageSpec& message_spec(MessageKind kind) noexcept {
  for (const auto& m : kMessageSet)
    if (m.kind == kind) return m;
  return kMessageSet[0];  // every kind has its row (tests/common/test_protocol_dbc.cpp)
}
// How many identifiers a message takes on the bus: one per pair, or one per pair and sender.
constexpr std::uint32_t id_count(const MessageSpec& m) noexcept { return (m.per_sender ? 2u : 1u) * kPairCount; }
// The identifier of a message of a pair; the role counts only for a message per sender.
constexpr std::uint32_t message_id(MessageKind kind, std::uint8_t pair, Role role = Role::hsi) noexcept {
  const auto& m = message_spec(kind);
  return m.per_sender ? m.base + 2u * pair + static_cast<std::uint32_t>(role) : m.base + pair;
}

constexpr std::uint32_t command_id(std::uint8_t pair) noexcept { return message_id(MessageKind::command, pair); }
constexpr std::uint32_t motion_id(std::uint8_t pair) noexcept { return message_id(MessageKind::motion, pair); }
constexpr std::uint32_t force_id(std::uint8_t pair) noexcept { return message_id(MessageKind::force, pair); }
constexpr std::uint32_t energy_id(std::uint8_t pair, Role role) noexcept {
  return message_id(MessageKind::energy, pair, role);
}
constexpr std::uint32_t settings_id(std::uint8_t pair, Role role) noexcept {
  return message_id(MessageKind::settings, pair, role);
}
constexpr std::uint32_t heartbeat_id(std::uint8_t pair, Role role) noexcept {
  return message_id(MessageKind::heartbeat, pair, role);
}

struct FrameAddress {
  MessageKind kind{};
  std::uint8_t pair = 0;
  Role role = Role::hsi;  // the sender's role (heartbeat, energy, settings); HSI for motion, TOP for force; unused
                          // for command
};

// What an identifier means, or unknown_id.
constexpr DecodeError classify(std::uint32_t id, FrameAddress& out) noexcept {
  for (const auto& m : kMessageSet) {
    if (id < m.base || id >= m.base + id_count(m)) continue;
    const std::uint32_t offset = id - m.base;
    out = m.per_sender ? FrameAddress{m.kind, static_cast<std::uint8_t>(offset / 2), static_cast<Role>(offset % 2)}
                       : FrameAddress{m.kind, static_cast<std::uint8_t>(offset), m.sender};
    return DecodeError::none;
  }
  return DecodeError::unknown_id;
}

// A frame's message name in the DBC ("LeverHeartbeatTop").
constexpr std::string_view message_name(const FrameAddress& a) noexcept {
  const auto& m = message_spec(a.kind);
  return m.per_sender && a.role == Role::top ? m.top_name : m.name;
}

// ---- Scaling (docs/can-protocol.md justifies each choice) ----
// Position: one count of a 4096-line encoder read x4; int16 spans +-2 turns.
inline constexpr double kPositionLsbRad = 2.0 * std::numbers::pi / 16384.0;
// Velocity: 1 mrad/s; int16 spans +-32.767 rad/s, past the 20 rad/s a hand reaches.
inline constexpr double kVelocityLsb = 1e-3;
// Force: 10 uN in a signed 24-bit field, +-83.886 N: +-50 N with margin, 100x finer than the 1 mN asked.
inline constexpr double kForceLsb = 1e-5;
inline constexpr std::int32_t kForceCodeMax = (1 << 23) - 1;
inline constexpr std::int32_t kForceCodeMin = -(1 << 23);
// Port energy: 1 uJ in an unsigned 32-bit field that wraps (4294.97 J); docs/can-protocol.md, "Energy".
inline constexpr double kEnergyLsbJ = 1e-6;
// Deadband parameters in the command frame.
inline constexpr double kPLsb = 1e-4;        // p up to 6.5535
inline constexpr double kFloorLsb = 1e-3;    // rad/s or N, up to 65.535
inline constexpr double kFilterHzLsb = 0.1;  // up to 6553.5 Hz; 0 = off
// A lever repeats its settings frame this often besides sending it on every change: a host that starts listening,
// or lost the frame of a change, learns the settings within it, at 2 frames a second a lever (docs/can-protocol.md).
inline constexpr std::uint32_t kSettingsPeriodMs = 500;
// The settings frame's rolling counters: 6 bits each.
inline constexpr std::uint8_t kSettingsCountModulo = 64;

// Flags shared by both data frames.
struct DataFlags {
  bool value_saturated = false;              // position (motion) or force (force) hit its field's range
  bool velocity_saturated = false;           // motion only
  bool refresh = false;                      // sent to refresh the receiver's reference, not because of the deadband
  codec::Mode mode = codec::Mode::deadband;  // the model the receiver must use from this sample on
  // The first sample of a new stream (the sender armed, re-armed or rebooted): the receiver forgets every
  // earlier sample, sequence number and tick, so its model restarts exactly as the sender's did.
  bool restart = false;
};

// HSI -> TOP: velocity through the deadband, with the position riding on every frame (paper section III-A).
struct MotionMessage {
  std::int16_t position = 0;  // kPositionLsbRad
  std::int16_t velocity = 0;  // kVelocityLsb
  std::uint16_t tick = 0;     // sender's 1 ms sample tick, modulo 2^16
  std::uint8_t seq = 0;       // per-direction data sequence number
  DataFlags flags;
};

// TOP -> HSI: measured contact force through the deadband.
struct ForceMessage {
  std::int32_t force = 0;  // kForceLsb, 24 bits on the wire
  std::uint16_t tick = 0;
  std::uint8_t seq = 0;
  DataFlags flags;
};

// Either lever -> its peer, in the tick of a data frame (the passivity observer, firmware.md): the input energy
// the sender's port passed on since it armed (all of it unless the port keeps a reserve), cumulative and never
// decreasing, so the receiver can take the newest as the largest and drop older ones whatever order they come in.
struct EnergyMessage {
  std::uint32_t energy = 0;  // kEnergyLsbJ, modulo 2^32: the receiver adds the modular difference (below 2^31)
  std::uint16_t tick = 0;    // sender's 1 ms tick, modulo 2^16
  std::uint8_t epoch = 0;    // the sender's arming count modulo 256: a new epoch restarts the account
};

// Each lever -> host (and anyone listening), on every change and every kSettingsPeriodMs: the codec settings of
// the direction the lever sends (HSI: motion, TOP: force), in the command's units, with counters a host compares
// before and after a command to know the lever took it.
struct SettingsMessage {
  codec::Mode mode = codec::Mode::deadband;
  std::uint8_t changes = 0;     // set_deadband commands accepted since boot, modulo kSettingsCountModulo
  std::uint8_t tares = 0;       // tares completed since boot, modulo kSettingsCountModulo (0 without a gauge)
  bool taring = false;          // a tare is averaging now
  std::uint16_t p = 0;          // kPLsb
  std::uint16_t floor = 0;      // kFloorLsb
  std::uint16_t filter_hz = 0;  // kFilterHzLsb, 0 = off
  friend constexpr bool operator==(const SettingsMessage&, const SettingsMessage&) noexcept = default;
};

// A non-negative parameter as the code of a 16-bit field of `lsb`: the nearest, clipped to the field (a
// configuration may hold more digits, or more range, than the command carries).
constexpr std::uint16_t unsigned_code(double value, double lsb) noexcept {
  const double code = value / lsb + 0.5;
  if (!(code >= 1.0)) return 0;  // NaN too
  if (code >= 65535.0) return 65535;
  return static_cast<std::uint16_t>(code);
}

// Stable numbers: on the wire in heartbeats.
enum class LeverState : std::uint8_t { init = 0, disarmed = 1, armed = 2, fault = 3, homing = 4 };

// The one spelling of a state, in status lines, on screens and in messages.
constexpr std::string_view name(LeverState state) noexcept {
  switch (state) {
    case LeverState::init:
      return "init";
    case LeverState::disarmed:
      return "disarmed";
    case LeverState::armed:
      return "armed";
    case LeverState::fault:
      return "fault";
    case LeverState::homing:
      return "homing";
  }
  return "unknown";
}

struct HeartbeatMessage {
  LeverState state = LeverState::init;
  bool position_valid = false;  // homed, or an absolute encoder: the position is in lever coordinates
  // The arming handshake. Over a delayed link a lever that re-arms still receives its peer's heartbeats from
  // before the peer's own re-arm ("armed", then "fault"), which looked like a peer that armed with it and left.
  // So each lever says which of its peer's armings it has heard, and a peer's state counts only once it echoes
  // this lever's current arming. One bit each: stale heartbeats are from the arming just before.
  bool arming_parity = false;        // parity of this lever's armings so far
  bool peer_arming_parity = false;   // the peer's arming_parity, as last heard since this lever armed...
  bool peer_arming_known = false;    // ...if it has heard the peer since (else the bit above means nothing)
  std::uint16_t faults = 0;          // latched fault bits (faults.hpp)
  std::uint8_t last_data_seq = 0;    // sequence number of the sender's last data frame
  std::uint8_t seq_gaps = 0;         // data frames found missing, saturating
  std::uint8_t rejected_frames = 0;  // frames that failed to decode, saturating
  std::uint8_t counter = 0;          // heartbeat count, rolling
  std::uint8_t encoder_errors = 0;   // illegal quadrature transitions, saturating
};

// Stable numbers: on the wire.
enum class Opcode : std::uint8_t { arm = 1, disarm = 2, rearm = 3, tare = 4, set_deadband = 5, home = 6 };
inline constexpr Opcode kAllOpcodes[] = {Opcode::arm,  Opcode::disarm, Opcode::rearm,
                                         Opcode::home, Opcode::tare,   Opcode::set_deadband};
// A command's name, as lever-ctl takes it and the tools show it.
constexpr std::string_view name(Opcode op) noexcept {
  switch (op) {
    case Opcode::arm:
      return "arm";
    case Opcode::disarm:
      return "disarm";
    case Opcode::rearm:
      return "rearm";
    case Opcode::tare:
      return "tare";
    case Opcode::set_deadband:
      return "set-deadband";
    case Opcode::home:
      return "home";
  }
  return "unknown";
}
enum class Direction : std::uint8_t { motion = 0, force = 1 };

struct CommandMessage {
  Opcode opcode = Opcode::arm;
  bool to_hsi = true;
  bool to_top = true;
  // set_deadband only:
  Direction direction = Direction::motion;
  codec::Mode mode = codec::Mode::deadband;
  std::uint16_t p = 0;          // kPLsb
  std::uint16_t floor = 0;      // kFloorLsb
  std::uint16_t filter_hz = 0;  // kFilterHzLsb
};

// The codec's settings as the set_deadband command and the settings frame both carry them, in kPLsb, kFloorLsb and
// kFilterHzLsb steps: one conversion each way and one comparison, for the levers and every host that reads or
// writes them.
template <typename M>
concept CarriesCodecSettings = std::is_same_v<M, SettingsMessage> || std::is_same_v<M, CommandMessage>;

template <CarriesCodecSettings M>
constexpr codec::Config<double> codec_settings(const M& m) noexcept {
  return {m.mode, m.p * kPLsb, m.floor * kFloorLsb, m.filter_hz * kFilterHzLsb};
}

// Each value the nearest step, clipped to its field (unsigned_code).
template <CarriesCodecSettings M>
constexpr void set_codec_settings(M& m, const codec::Config<double>& c) noexcept {
  m.mode = c.mode;
  m.p = unsigned_code(c.p, kPLsb);
  m.floor = unsigned_code(c.floor, kFloorLsb);
  m.filter_hz = unsigned_code(c.filter_hz, kFilterHzLsb);
}

template <CarriesCodecSettings A, CarriesCodecSettings B>
constexpr bool same_codec_settings(const A& a, const B& b) noexcept {
  return a.mode == b.mode && a.p == b.p && a.floor == b.floor && a.filter_hz == b.filter_hz;
}

// ---- Packing: every field fits by construction of the types, so packing cannot fail ----

namespace detail {
constexpr std::uint64_t pack_flags(const DataFlags& f) noexcept {
  return (f.value_saturated ? 1u : 0u) | (f.velocity_saturated ? 2u : 0u) | (f.refresh ? 4u : 0u) |
         (f.mode == codec::Mode::predictive ? 8u : 0u) | (f.restart ? 16u : 0u);
}
constexpr DecodeError unpack_flags(std::uint64_t raw, DataFlags& f) noexcept {
  if (raw & 0xE0u) return DecodeError::out_of_range;  // reserved bits
  f.value_saturated = raw & 1u;
  f.velocity_saturated = raw & 2u;
  f.refresh = raw & 4u;
  f.mode = (raw & 8u) ? codec::Mode::predictive : codec::Mode::deadband;
  f.restart = raw & 16u;
  return DecodeError::none;
}
constexpr CanFrame frame(std::uint32_t id) noexcept { return CanFrame{id, 8, {}}; }
}  // namespace detail

constexpr CanFrame pack(const MotionMessage& m, std::uint8_t pair) noexcept {
  CanFrame f = detail::frame(motion_id(pair));
  put_signed_bits(f.data, 0, 16, m.position);
  put_signed_bits(f.data, 16, 16, m.velocity);
  put_bits(f.data, 32, 16, m.tick);
  put_bits(f.data, 48, 8, m.seq);
  put_bits(f.data, 56, 8, detail::pack_flags(m.flags));
  return f;
}

constexpr CanFrame pack(const ForceMessage& m, std::uint8_t pair) noexcept {
  CanFrame f = detail::frame(force_id(pair));
  const std::int32_t code = m.force > kForceCodeMax ? kForceCodeMax : m.force < kForceCodeMin ? kForceCodeMin : m.force;
  put_signed_bits(f.data, 0, 24, code);
  put_bits(f.data, 24, 16, m.tick);
  put_bits(f.data, 40, 8, m.seq);
  // A force outside the 24-bit field is clipped, and says so.
  DataFlags flags = m.flags;
  flags.value_saturated = flags.value_saturated || code != m.force;
  put_bits(f.data, 48, 8, detail::pack_flags(flags));
  return f;
}

constexpr CanFrame pack(const EnergyMessage& m, std::uint8_t pair, Role role) noexcept {
  CanFrame f = detail::frame(energy_id(pair, role));
  put_bits(f.data, 0, 32, m.energy);
  put_bits(f.data, 32, 16, m.tick);
  put_bits(f.data, 48, 8, m.epoch);
  return f;
}

// The counters wrap: only their low 6 bits go on the wire.
constexpr CanFrame pack(const SettingsMessage& m, std::uint8_t pair, Role role) noexcept {
  CanFrame f = detail::frame(settings_id(pair, role));
  put_bits(f.data, 0, 2, static_cast<std::uint8_t>(m.mode));
  put_bits(f.data, 2, 6, m.changes);
  put_bits(f.data, 8, 6, m.tares);
  put_bits(f.data, 14, 1, m.taring);
  put_bits(f.data, 16, 16, m.p);
  put_bits(f.data, 32, 16, m.floor);
  put_bits(f.data, 48, 16, m.filter_hz);
  return f;
}

constexpr CanFrame pack(const HeartbeatMessage& m, std::uint8_t pair, Role role) noexcept {
  CanFrame f = detail::frame(heartbeat_id(pair, role));
  put_bits(f.data, 0, 4, static_cast<std::uint8_t>(m.state));
  put_bits(f.data, 4, 1, m.position_valid);
  put_bits(f.data, 5, 1, m.arming_parity);
  put_bits(f.data, 6, 1, m.peer_arming_parity);
  put_bits(f.data, 7, 1, m.peer_arming_known);
  put_bits(f.data, 8, 16, m.faults);
  put_bits(f.data, 24, 8, m.last_data_seq);
  put_bits(f.data, 32, 8, m.seq_gaps);
  put_bits(f.data, 40, 8, m.rejected_frames);
  put_bits(f.data, 48, 8, m.counter);
  put_bits(f.data, 56, 8, m.encoder_errors);
  return f;
}

constexpr CanFrame pack(const CommandMessage& m, std::uint8_t pair) noexcept {
  CanFrame f = detail::frame(command_id(pair));
  put_bits(f.data, 0, 8, static_cast<std::uint8_t>(m.opcode));
  put_bits(f.data, 8, 1, m.to_hsi);
  put_bits(f.data, 9, 1, m.to_top);
  put_bits(f.data, 10, 1, static_cast<std::uint8_t>(m.direction));
  put_bits(f.data, 11, 2, static_cast<std::uint8_t>(m.mode));
  put_bits(f.data, 16, 16, m.p);
  put_bits(f.data, 32, 16, m.floor);
  put_bits(f.data, 48, 16, m.filter_hz);
  return f;
}

// ---- Decoding: the id's kind must match, the DLC must be 8, enumerations must be defined ----

namespace detail {
constexpr DecodeError expect(const CanFrame& f, MessageKind kind, FrameAddress& address) noexcept {
  if (const auto e = classify(f.id, address); e != DecodeError::none) return e;
  if (address.kind != kind) return DecodeError::unknown_id;
  if (f.dlc != 8) return DecodeError::wrong_dlc;
  return DecodeError::none;
}
}  // namespace detail

constexpr DecodeError decode(const CanFrame& f, MotionMessage& m, FrameAddress& address) noexcept {
  if (const auto e = detail::expect(f, MessageKind::motion, address); e != DecodeError::none) return e;
  m.position = static_cast<std::int16_t>(get_signed_bits(f.data, 0, 16));
  m.velocity = static_cast<std::int16_t>(get_signed_bits(f.data, 16, 16));
  m.tick = static_cast<std::uint16_t>(get_bits(f.data, 32, 16));
  m.seq = static_cast<std::uint8_t>(get_bits(f.data, 48, 8));
  return detail::unpack_flags(get_bits(f.data, 56, 8), m.flags);
}

constexpr DecodeError decode(const CanFrame& f, ForceMessage& m, FrameAddress& address) noexcept {
  if (const auto e = detail::expect(f, MessageKind::force, address); e != DecodeError::none) return e;
  if (get_bits(f.data, 56, 8) != 0) return DecodeError::out_of_range;  // reserved byte
  m.force = static_cast<std::int32_t>(get_signed_bits(f.data, 0, 24));
  m.tick = static_cast<std::uint16_t>(get_bits(f.data, 24, 16));
  m.seq = static_cast<std::uint8_t>(get_bits(f.data, 40, 8));
  if (const auto e = detail::unpack_flags(get_bits(f.data, 48, 8), m.flags); e != DecodeError::none) return e;
  return m.flags.velocity_saturated ? DecodeError::out_of_range : DecodeError::none;
}

constexpr DecodeError decode(const CanFrame& f, EnergyMessage& m, FrameAddress& address) noexcept {
  if (const auto e = detail::expect(f, MessageKind::energy, address); e != DecodeError::none) return e;
  if (get_bits(f.data, 56, 8) != 0) return DecodeError::out_of_range;  // reserved byte
  m.energy = static_cast<std::uint32_t>(get_bits(f.data, 0, 32));
  m.tick = static_cast<std::uint16_t>(get_bits(f.data, 32, 16));
  m.epoch = static_cast<std::uint8_t>(get_bits(f.data, 48, 8));
  return DecodeError::none;
}

constexpr DecodeError decode(const CanFrame& f, SettingsMessage& m, FrameAddress& address) noexcept {
  if (const auto e = detail::expect(f, MessageKind::settings, address); e != DecodeError::none) return e;
  const auto mode = get_bits(f.data, 0, 2);
  if (mode > static_cast<std::uint8_t>(codec::Mode::predictive)) return DecodeError::out_of_range;
  if (get_bits(f.data, 15, 1) != 0) return DecodeError::out_of_range;  // reserved
  m.mode = static_cast<codec::Mode>(mode);
  m.changes = static_cast<std::uint8_t>(get_bits(f.data, 2, 6));
  m.tares = static_cast<std::uint8_t>(get_bits(f.data, 8, 6));
  m.taring = get_bits(f.data, 14, 1);
  m.p = static_cast<std::uint16_t>(get_bits(f.data, 16, 16));
  m.floor = static_cast<std::uint16_t>(get_bits(f.data, 32, 16));
  m.filter_hz = static_cast<std::uint16_t>(get_bits(f.data, 48, 16));
  return DecodeError::none;
}

constexpr DecodeError decode(const CanFrame& f, HeartbeatMessage& m, FrameAddress& address) noexcept {
  if (const auto e = detail::expect(f, MessageKind::heartbeat, address); e != DecodeError::none) return e;
  const auto state = get_bits(f.data, 0, 4);
  if (state > static_cast<std::uint8_t>(LeverState::homing)) return DecodeError::out_of_range;
  m.state = static_cast<LeverState>(state);
  m.position_valid = get_bits(f.data, 4, 1);
  m.arming_parity = get_bits(f.data, 5, 1);
  m.peer_arming_parity = get_bits(f.data, 6, 1);
  m.peer_arming_known = get_bits(f.data, 7, 1);
  m.faults = static_cast<std::uint16_t>(get_bits(f.data, 8, 16));
  m.last_data_seq = static_cast<std::uint8_t>(get_bits(f.data, 24, 8));
  m.seq_gaps = static_cast<std::uint8_t>(get_bits(f.data, 32, 8));
  m.rejected_frames = static_cast<std::uint8_t>(get_bits(f.data, 40, 8));
  m.counter = static_cast<std::uint8_t>(get_bits(f.data, 48, 8));
  m.encoder_errors = static_cast<std::uint8_t>(get_bits(f.data, 56, 8));
  return DecodeError::none;
}

constexpr DecodeError decode(const CanFrame& f, CommandMessage& m, FrameAddress& address) noexcept {
  if (const auto e = detail::expect(f, MessageKind::command, address); e != DecodeError::none) return e;
  const auto opcode = get_bits(f.data, 0, 8);
  if (opcode < static_cast<std::uint8_t>(Opcode::arm) || opcode > static_cast<std::uint8_t>(Opcode::home))
    return DecodeError::out_of_range;
  const auto mode = get_bits(f.data, 11, 2);
  if (mode > static_cast<std::uint8_t>(codec::Mode::predictive)) return DecodeError::out_of_range;
  if (get_bits(f.data, 13, 3) != 0) return DecodeError::out_of_range;  // reserved
  m.opcode = static_cast<Opcode>(opcode);
  m.to_hsi = get_bits(f.data, 8, 1);
  m.to_top = get_bits(f.data, 9, 1);
  m.direction = static_cast<Direction>(get_bits(f.data, 10, 1));
  m.mode = static_cast<codec::Mode>(mode);
  m.p = static_cast<std::uint16_t>(get_bits(f.data, 16, 16));
  m.floor = static_cast<std::uint16_t>(get_bits(f.data, 32, 16));
  m.filter_hz = static_cast<std::uint16_t>(get_bits(f.data, 48, 16));
  return DecodeError::none;
}

}  // namespace lever::protocol
