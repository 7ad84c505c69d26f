#pragma once
// The hardware the lever core touches, as C++20 concepts. The board (libgpiod, libmodbus, SocketCAN) and
// the HIL each provide types that satisfy them; the core is a template over them, so the 1 kHz path has no
// virtual calls and no hardware headers.
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>

#include "lever/fw/tick.hpp"
#include "lever/protocol/can_frame.hpp"

namespace lever::fw {

// ---- Encoder ----

// A and B line levels packed as (A << 1) | B.
using AbState = std::uint8_t;
constexpr AbState ab(bool a, bool b) noexcept { return static_cast<AbState>((a ? 2 : 0) | (b ? 1 : 0)); }

// One edge on the A or B line as the edge source saw it: the A/B levels just after it, and whether the
// index (Z) line rose at this position (an index-only event repeats the current A/B levels).
struct EncoderEdge {
  AbState levels = 0;
  bool index = false;
};

// What one drain brought. `lost` says what the source knows of edges it could not deliver: a full kernel event
// FIFO, two edges of one direction in a row on a line, an edge older than one already delivered, line levels that
// disagree with the decoded state (libgpiod v1 gives no sequence numbers). Any non-zero value means the count can
// no longer be trusted; the exact number is a best estimate (at least 1).
struct EdgeDrain {
  std::size_t count = 0;
  std::uint32_t lost = 0;
};

// Encoder as edge events (libgpiod on the board, the simulated encoder in the HIL): oldest first, up to
// `capacity` at a time, never blocking. levels(): the A/B levels after the newest edge delivered, and before
// the first drain the levels the lines had when they were opened. An edge only says where the lines went, so
// a decoder that waited for the first edge to learn where they were would lose that edge's count.
template <typename E>
concept EdgeEncoderPort = requires(E& e, const E& ce, EncoderEdge* out, std::size_t capacity) {
  { e.drain_edges(out, capacity) } -> std::same_as<EdgeDrain>;
  { ce.levels() } -> std::same_as<AbState>;
};

// Encoder with a hardware counter (a timer in encoder mode, a kernel counter device): the raw register,
// which wraps at the width the lever's config declares (counter_bits); the core unwraps it by sign-extended
// differences, so it must be read at least once per half a wrap.
template <typename E>
concept CountingEncoderPort = requires(E& e) {
  { e.read_counts() } -> std::same_as<std::uint32_t>;
};

template <typename E>
concept EncoderPort = EdgeEncoderPort<E> || CountingEncoderPort<E>;

// ---- Strain gauge ----

// One amplifier reading as the HAL delivers it, in the amplifier's units (ADC counts, or what a Modbus
// register map scales to); the core's gauge calibration turns it into newtons.
struct ForceReading {
  double raw = 0.0;
  Tick tick = 0;           // when it was taken, on the firmware's clock
  bool error = false;      // the transport (Modbus) or the amplifier reported a failed reading
  bool saturated = false;  // the source says its input is at its range end (an amplifier's overload code)
};

// The newest amplifier reading, with its timestamp; empty before the first.
template <typename F>
concept ForcePort = requires(F& f) {
  { f.latest() } -> std::same_as<std::optional<ForceReading>>;
};

// ---- Motor ----

struct MotorCommand {
  double torque_nm = 0.0;
  bool enable = false;
};

template <typename M>
concept MotorPort = requires(M& m, const MotorCommand& command) {
  m.command(command);
  { m.driver_fault() } -> std::convertible_to<bool>;
};

// ---- CAN ----

// Non-blocking queues: receive returns false when empty, send false when the queue is full.
template <typename C>
concept CanPort = requires(C& c, protocol::CanFrame& in, const protocol::CanFrame& out) {
  { c.receive(in) } -> std::convertible_to<bool>;
  { c.send(out) } -> std::convertible_to<bool>;
};

// Optional: the controller can say it cannot reach the bus (bus-off, the interface down or gone). The core
// then latches CAN_BUS at once instead of waiting out the comms timeout.
template <typename C>
concept HasBusFault = requires(const C& c) {
  { c.bus_fault() } -> std::convertible_to<bool>;
};

// ---- The board ----

template <typename H>
using EncoderOf = std::remove_cvref_t<decltype(std::declval<H&>().encoder())>;
template <typename H>
using ForceOf = std::remove_cvref_t<decltype(std::declval<H&>().force())>;
template <typename H>
using MotorOf = std::remove_cvref_t<decltype(std::declval<H&>().motor())>;
template <typename H>
using CanOf = std::remove_cvref_t<decltype(std::declval<H&>().can())>;

template <typename H>
concept HasPorts = requires(H& h) {
  h.encoder();
  h.force();
  h.motor();
  h.can();
};

// A board: one port of each kind.
template <typename H>
concept LeverHal =
    HasPorts<H> && EncoderPort<EncoderOf<H>> && ForcePort<ForceOf<H>> && MotorPort<MotorOf<H>> && CanPort<CanOf<H>>;

// A board made of one port of each kind, for the simple cases (a stand-in HAL, a board runner): the ports are
// its members, aggregate-initialized in this order.
template <typename E, typename F, typename M, typename C>
struct Ports {
  E encoder_;
  F force_;
  M motor_;
  C can_;
  E& encoder() { return encoder_; }
  F& force() { return force_; }
  M& motor() { return motor_; }
  C& can() { return can_; }
};

// Optional: a monotonic nanosecond clock, with which the core measures how long each step() takes. Boards
// have one; the HIL's simulated time has none worth measuring.
template <typename H>
concept HasStepClock = requires(H& h) {
  { h.monotonic_ns() } -> std::convertible_to<std::uint64_t>;
};

}  // namespace lever::fw
