#pragma once
// The HSI's part of a lever: its velocity goes out through the deadband with the position on every frame; the
// TOP's contact force comes back, is reconstructed and displayed on the operator's hand. Everything shared
// with the TOP (sensors, supervisor, link, safety) is in lever.hpp.
#include <cstdint>
#include <optional>

#include "lever/fw/controllers.hpp"
#include "lever/fw/data_channel.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/fw/passivity.hpp"
#include "lever/fw/telemetry.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

class HsiRole {
 public:
  static constexpr protocol::Role kRole = protocol::Role::hsi;
  static constexpr protocol::Role kPeer = protocol::Role::top;
  static constexpr protocol::MessageKind kReceives = protocol::MessageKind::force;
  static constexpr protocol::Direction kSends = protocol::Direction::motion;
  // In fault the HSI displays nothing: a lever that holds would trap the operator's hand.
  static constexpr bool kHoldsOnFault = false;
  using Sender = DataSender<std::int16_t>;
  using Receiver = DataReceiver<std::int32_t>;

  explicit constexpr HsiRole(const LeverConfig& c) noexcept
      : display_(c.display),
        sender_(c.motion_codec, velocity_wire(), c.refresh_period, c.rest_repeat),
        receiver_(force_wire()),
        stale_after_(2 * c.refresh_period),
        motion_velocity_(c.motion_velocity),
        passivity_(c.passivity),
        arm_m_(c.display.lever_arm_m) {}

  static constexpr bool addressed(const protocol::CommandMessage& m) noexcept { return m.to_hsi; }
  static constexpr bool uses_gauge(const LeverConfig& c) noexcept {
    return c.use_force_sensor && c.display.closed_loop;
  }

  constexpr const Sender& sender() const noexcept { return sender_; }
  constexpr const Receiver& receiver() const noexcept { return receiver_; }
  constexpr Receiver& receiver() noexcept { return receiver_; }
  constexpr Sender& sender() noexcept { return sender_; }
  constexpr const ForceDisplay& display() const noexcept { return display_; }
  constexpr const PassivityPort& passivity() const noexcept { return passivity_; }
  constexpr PassivityPort& passivity() noexcept { return passivity_; }

  // A force frame for this pair. Returns the decode error, and in `used` whether it fed the model.
  protocol::DecodeError receive(const protocol::CanFrame& frame, Tick now, bool& used) noexcept {
    protocol::FrameAddress address;
    protocol::ForceMessage m;
    const auto error = protocol::decode(frame, m, address);
    used = error == protocol::DecodeError::none && receiver_.accept(now, m.tick, m.seq, m.flags, m.force);
    return error;
  }

  constexpr void on_armed(LeverTelemetry&) noexcept {
    sender_.restart();
    receiver_.expire();
    display_.reset();
    passivity_.on_armed();
  }

  // Torque while armed: the reconstructed force on the hand; nothing (zero force) while the stream is stale.
  double control(Tick now, double dt, LeverTelemetry& t) noexcept {
    t.remote = receiver_.value_at(now, stale_after_);
    // The port's output is the displayed force: its torque (-F arm) on the lever moving at the lever's
    // velocity is the power the channel gives the operator's side.
    double force = t.remote.value_or(0.0);
    force *= passivity_.limit(-force * arm_m_ * t.velocity_rad_s, dt, passivity_.config().display_spend_time_s);
    if (t.remote) t.remote = force;
    t.dissipated_energy_j = passivity_.state().dissipated_j;
    t.observed_energy_j = passivity_.state().observed_j;
    const double* own = t.force_n ? &*t.force_n : nullptr;
    return display_.update(force, own, t.velocity_rad_s, dt);
  }

  std::optional<OutgoingData> transmit(Tick now, const LeverTelemetry& t, std::uint8_t pair) noexcept {
    const double velocity = motion_velocity_ == MotionVelocity::difference        ? t.velocity_difference_rad_s
                            : motion_velocity_ == MotionVelocity::adaptive_window ? t.velocity_window_rad_s
                                                                                  : t.velocity_rad_s;
    const auto out = sender_.offer(now, velocity);
    if (!out.send) return std::nullopt;
    bool position_saturated = false;
    protocol::MotionMessage m;
    m.position = position_wire().encode(t.position_rad, position_saturated);
    m.velocity = out.code;
    m.tick = static_cast<std::uint16_t>(now & 0xFFFFu);
    m.seq = out.seq;
    m.flags = {position_saturated, out.saturated, out.refresh, out.mode, out.restart};
    return OutgoingData{protocol::pack(m, pair), out.refresh, out.cause};
  }

  // set_deadband for the motion direction, which the HSI sends.
  constexpr void reconfigure(const codec::Config<double>& c) noexcept { sender_.reconfigure(c); }

 private:
  ForceDisplay display_;
  Sender sender_;
  Receiver receiver_;
  Tick stale_after_;
  MotionVelocity
      motion_velocity_;  // two refresh periods without data: the sender stopped, not merely stayed inside its deadband
  PassivityPort passivity_;
  double arm_m_;
};

}  // namespace lever::fw
