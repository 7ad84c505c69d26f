#pragma once
// The hardware the lever core touches, as C++20 concepts. The board (libgpiod, libmodbus, SocketCAN) and
// the HIL each provide types that satisfy them; the core is a template over them, so the 1 kHz path has no
// virtual calls and no hardware headers.
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>

#include "lever/fw/quadrature_decoder.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/protocol/can_frame.hpp"

namespace lever::fw {

// Encoder as edge events: A/B levels after each edge, oldest first, up to `capacity` at a time.
template <typename E>
concept EdgeEncoderPort = requires(E& e, AbState* out, std::size_t capacity) {
  { e.drain_edges(out, capacity) } -> std::convertible_to<std::size_t>;
};

// Encoder with a hardware counter (a timer in encoder mode).
template <typename E>
concept CountingEncoderPort = requires(E& e) {
  { e.read_counts() } -> std::convertible_to<std::int32_t>;
};

// The newest amplifier reading, with its timestamp; empty before the first.
template <typename F>
concept ForcePort = requires(F& f) {
  { f.latest() } -> std::same_as<std::optional<ForceReading>>;
};

struct MotorCommand {
  double torque_nm = 0.0;
  bool enable = false;
};

template <typename M>
concept MotorPort = requires(M& m, const MotorCommand& command) {
  m.command(command);
  { m.driver_fault() } -> std::convertible_to<bool>;
};

// Non-blocking CAN queues: receive returns false when empty, send false when the queue is full.
template <typename C>
concept CanPort = requires(C& c, protocol::CanFrame& in, const protocol::CanFrame& out) {
  { c.receive(in) } -> std::convertible_to<bool>;
  { c.send(out) } -> std::convertible_to<bool>;
};

template <typename H>
using EncoderOf = std::remove_cvref_t<decltype(std::declval<H&>().encoder())>;

template <typename H>
concept LeverHal = requires(H& h) {
  h.encoder();
  h.force();
  h.motor();
  h.can();
}
&&(EdgeEncoderPort<EncoderOf<H>> || CountingEncoderPort<EncoderOf<H>>)&&ForcePort<std::remove_cvref_t<
    decltype(std::declval<H&>()
                 .force())>>&& MotorPort<std::
                                             remove_cvref_t<
                                                 decltype(std::declval<H&>()
                                                              .motor())>>&& CanPort<std::
                                                                                        remove_cvref_t<
                                                                                            decltype(std::declval<H&>()
                                                                                                         .can())>>;

}  // namespace lever::fw
