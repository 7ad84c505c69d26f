#pragma once
// The TOP's part of a lever: the HSI's reconstructed motion is tracked by a position controller, and the
// measured contact force goes back through the deadband. Everything shared with the HSI (sensors,
// supervisor, link, safety) is in lever.hpp.
#include <cstdint>
#include <limits>
#include <optional>

#include "lever/fw/controllers.hpp"
#include "lever/fw/data_channel.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/fw/passivity.hpp"
#include "lever/fw/telemetry.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

class TopRole {
 public:
  static constexpr protocol::Role kRole = protocol::Role::top;
  static constexpr protocol::Role kPeer = protocol::Role::hsi;
  static constexpr protocol::MessageKind kReceives = protocol::MessageKind::motion;
  static constexpr protocol::Direction kSends = protocol::Direction::force;
  // In fault the TOP holds where it was, gently, for a while: letting go could drop a tool on the wall.
  static constexpr bool kHoldsOnFault = true;
  using Sender = DataSender<std::int32_t>;
  using Receiver = DataReceiver<std::int16_t>;

  explicit constexpr TopRole(const LeverConfig& c) noexcept
      : controller_(c.position),
        sender_(c.force_codec, force_wire(), c.refresh_period, c.rest_repeat),
        receiver_(velocity_wire()),
        stale_after_(2 * c.refresh_period),
        approach_speed_(c.position.approach_speed_rad_s),
        passivity_(c.passivity),
        arm_m_(c.display.lever_arm_m),
        contact_threshold_nm_(c.display.contact_threshold_n * c.display.lever_arm_m),
        // kp 0 (a config that turns the position loop off) presses nothing: no bound on the pull
        max_press_rad_(c.position.kp > 0.0 ? c.torque_limit_nm / c.position.kp
                                           : std::numeric_limits<double>::infinity()) {}

  static constexpr bool addressed(const protocol::CommandMessage& m) noexcept { return m.to_top; }
  static constexpr bool uses_gauge(const LeverConfig&) noexcept { return true; }

  constexpr const Sender& sender() const noexcept { return sender_; }
  constexpr const Receiver& receiver() const noexcept { return receiver_; }
  constexpr Receiver& receiver() noexcept { return receiver_; }
  constexpr Sender& sender() noexcept { return sender_; }
  constexpr const PositionController& controller() const noexcept { return controller_; }
  constexpr const PassivityPort& passivity() const noexcept { return passivity_; }
  constexpr PassivityPort& passivity() noexcept { return passivity_; }

  // A motion frame for this pair. The position rides on every velocity frame and resets the integrated
  // reference (paper section III-A).
  protocol::DecodeError receive(const protocol::CanFrame& frame, Tick now, bool& used) noexcept {
    protocol::FrameAddress address;
    protocol::MotionMessage m;
    const auto error = protocol::decode(frame, m, address);
    used = error == protocol::DecodeError::none && receiver_.accept(now, m.tick, m.seq, m.flags, m.velocity);
    if (used) {
      position_ref_ = position_wire().decode(m.position);
      have_motion_ = true;
    }
    return error;
  }

  // Until the HSI's motion arrives, the TOP holds where it is.
  constexpr void on_armed(LeverTelemetry& t) noexcept {
    sender_.restart();
    receiver_.expire();
    position_ref_ = t.position_rad;
    tracked_ref_ = t.position_rad;
    have_motion_ = false;
    approaching_ = true;
    controller_.reset();
    passivity_.on_armed();
  }

  double control(Tick now, double dt, LeverTelemetry& t) noexcept {
    if (have_motion_) {
      // A stale stream leaves the reference where it was: the TOP holds instead of integrating old motion.
      t.remote = receiver_.value_at(now, stale_after_);
      t.velocity_ref_rad_s = t.remote.value_or(0.0);
      if (now != receiver_.last_arrival()) position_ref_ += t.velocity_ref_rad_s * dt;
    } else {
      t.velocity_ref_rad_s = 0.0;
    }
    // Approach: the reference the controller sees walks to the HSI's at a bounded speed, then follows it.
    if (approaching_) {
      const double step = approach_speed_ * dt;
      const double gap = position_ref_ - tracked_ref_;
      if (gap > step) {
        tracked_ref_ += step;
      } else if (gap < -step) {
        tracked_ref_ -= step;
      } else if (have_motion_) {
        approaching_ = false;  // caught up with the HSI's motion, not merely with its own start
      }
      if (approaching_) t.velocity_ref_rad_s = 0.0;
      passive_ref_ = tracked_ref_;  // the passive reference starts where the approach ends
    }
    if (!approaching_) {
      // The port's output is the commanded velocity; with the measured contact force (x arm) it is the power
      // the channel gives the wall's side. A reading within the contact threshold (0.1 N, twenty times the
      // gauge's filtered noise) is no contact: the lever pushes on nothing, and counting gauge noise as force
      // would charge free motion for energy it does not carry. What that leaves out, at most the threshold
      // times the travel while pressing that lightly, is under a microjoule against the 20 kN/m wall.
      const double gauge_nm = t.force_n.value_or(0.0) * arm_m_;
      const bool in_contact = gauge_nm > contact_threshold_nm_ || gauge_nm < -contact_threshold_nm_;
      const double force_nm = in_contact ? gauge_nm : 0.0;
      if (passivity_.config().mode == PassivityMode::tdpa) {
        // The reference integrates the passive velocity instead of jumping to each frame's position. The HSI's
        // position (position_ref_, reset by every motion frame) pulls it along, which closes the drift the
        // controller left. In contact that drift is the depth the HSI went past the wall while the TOP had no
        // energy to follow; the pull there aims no further past the lever than the position loop can press
        // with the motor's torque (torque limit / kp), so the TOP presses as the operator does, up to the
        // motor's force, and its demand never sits above the torque limit that trips the protection. Without
        // the pull in contact, the press stayed a few mrad deep (1-2 N) and the HSI's one-count velocity pulses
        // bounced the lever off the wall at about 50 Hz (docs/firmware.md, "Passivity under delay").
        double target = position_ref_;
        if (in_contact) {
          if (target > t.position_rad + max_press_rad_) target = t.position_rad + max_press_rad_;
          if (target < t.position_rad - max_press_rad_) target = t.position_rad - max_press_rad_;
        }
        double velocity = t.velocity_ref_rad_s + passivity_.config().drift_gain_per_s * (target - passive_ref_);
        velocity *= passivity_.limit(force_nm * velocity, dt);
        passive_ref_ += velocity * dt;
        t.velocity_ref_rad_s = velocity;
        tracked_ref_ = passive_ref_;
      } else {
        passivity_.limit(force_nm * t.velocity_ref_rad_s, dt);
        tracked_ref_ = position_ref_;
      }
    }
    t.dissipated_energy_j = passivity_.state().dissipated_j;
    t.observed_energy_j = passivity_.state().observed_j;
    t.position_ref_rad = tracked_ref_;
    return controller_.update(tracked_ref_, t.velocity_ref_rad_s, t.position_rad, t.velocity_rad_s, dt);
  }

  std::optional<OutgoingData> transmit(Tick now, const LeverTelemetry& t, std::uint8_t pair) noexcept {
    if (!t.force_n) return std::nullopt;  // stale gauge: the supervisor is already taking the lever down
    const auto out = sender_.offer(now, *t.force_n);
    if (!out.send) return std::nullopt;
    protocol::ForceMessage m;
    m.force = out.code;
    m.tick = static_cast<std::uint16_t>(now & 0xFFFFu);
    m.seq = out.seq;
    m.flags = {out.saturated, false, out.refresh, out.mode, out.restart};
    return OutgoingData{protocol::pack(m, pair), out.refresh, out.cause};
  }

  // set_deadband for the force direction, which the TOP sends.
  constexpr void reconfigure(const codec::Config<double>& c) noexcept { sender_.reconfigure(c); }

 private:
  PositionController controller_;
  Sender sender_;
  Receiver receiver_;
  Tick stale_after_;
  double approach_speed_;
  double position_ref_ = 0.0;  // the HSI's position as received and integrated
  double tracked_ref_ = 0.0;   // what the controller tracks
  bool have_motion_ = false;
  bool approaching_ = false;
  PassivityPort passivity_;
  double arm_m_;
  double contact_threshold_nm_;
  double max_press_rad_;      // tdpa: how far the pull aims past the lever in contact, torque limit / kp
  double passive_ref_ = 0.0;  // tdpa: the reference the passive velocity integrates
};

}  // namespace lever::fw
