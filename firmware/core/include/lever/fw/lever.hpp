#pragma once
// The lever application, advanced by step(now) once per 1 ms tick: what both roles share (sensors, homing,
// the link, the supervisor, safety, the torque clamp, heartbeats), with the role's own behaviour (HsiRole,
// TopRole) as a compile-time policy, so the 1 kHz path has no role branches. No heap, no exceptions, no OS:
// everything it touches comes through the HAL (hal.hpp).
//
// Per tick: timing -> sensors -> frames from the bus -> faults -> control by state (homing, armed: the role,
// fault: the safe behaviour) -> clamp torque -> command the motor -> data, settings and heartbeat out.
#include <cstdint>
#include <optional>

#include "lever/fw/controllers.hpp"
#include "lever/fw/encoder_position.hpp"
#include "lever/fw/hal.hpp"
#include "lever/fw/homing.hpp"
#include "lever/fw/hsi_role.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/fw/link.hpp"
#include "lever/fw/quadrature_decoder.hpp"
#include "lever/fw/step_timing.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/fw/supervisor.hpp"
#include "lever/fw/telemetry.hpp"
#include "lever/fw/top_role.hpp"
#include "lever/fw/velocity_estimator.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

template <LeverHal H, typename Role>
class Lever {
 public:
  using role_type = Role;

  Lever(H& hal, const LeverConfig& config) noexcept
      : hal_(hal),
        config_(with_role(config)),
        decoder_(config.decoder),
        counter_(config.counter_bits),
        position_(config.counts_per_rev, config.homing.method == HomingMethod::absolute),
        velocity_(config.velocity),
        window_(config.adaptive_window),
        gauge_(config.gauge),
        homing_(config.homing),
        timing_(config.timing),
        role_(config),
        uses_gauge_(Role::uses_gauge(config)) {
    // The decoder starts where the lines are, so the first edge counts like every other one.
    if constexpr (EdgeEncoderPort<EncoderOf<H>>) decoder_.reset(hal.encoder().levels());
  }

  void step(Tick now) noexcept {
    begin(now);
    receive_frames(now);
    decide(now);
    if (supervisor_.armed()) transmit_data(now);
    end(now);
  }

  // step()'s two halves, for a controller that runs both levers of a pair (the paper's single PC): sample() both,
  // hand each data frame to the other lever, then act() both, so a sample reaches the other lever in the tick it
  // was taken, both ways. The data frame goes out in sample(), before this tick's frames and control: what it
  // carries comes from the sensors alone.
  void sample(Tick now) noexcept {
    begin(now);
    if (supervisor_.armed()) transmit_data(now);
  }
  void act(Tick now) noexcept {
    receive_frames(now);
    decide(now);
    end(now);
  }

  const LeverConfig& config() const noexcept { return config_; }
  const Supervisor& supervisor() const noexcept { return supervisor_; }
  const LeverTelemetry& telemetry() const noexcept { return telemetry_; }
  const LeverCounters& counters() const noexcept { return counters_; }
  const QuadratureDecoder& decoder() const noexcept { return decoder_; }
  const StrainGauge& gauge() const noexcept { return gauge_; }
  const VelocityEstimator& velocity_estimator() const noexcept { return velocity_; }
  const EncoderPosition& position() const noexcept { return position_; }
  const StepTiming& timing() const noexcept { return timing_; }
  const Role& role() const noexcept { return role_; }

  // Faults whose conditions hold now (what arm and re-arm check, and what ends an armed run).
  FaultBits active_faults(Tick now) const noexcept {
    FaultBits f = homing_faults();
    if (watchdog_.silent(now, config_.comms_timeout)) f |= bit(Fault::comms_timeout);
    if (uses_gauge_) {
      if (gauge_.state().stale) f |= bit(Fault::force_stale);
      if (gauge_.state().saturated) f |= bit(Fault::force_saturated);
    }
    if (saturated_ticks_ > config_.torque_saturation_ticks) f |= bit(Fault::torque_limit);
    if (position_.valid() &&
        (telemetry_.position_rad < config_.position_min_rad || telemetry_.position_rad > config_.position_max_rad))
      f |= bit(Fault::position_limit);
    if (supervisor_.armed() && peer_left_) f |= bit(Fault::peer_state);
    return f;
  }

 private:
  static constexpr std::size_t kMaxEdgesPerRead = 64;
  static constexpr std::size_t kMaxFramesPerTick = 16;  // bounds the loop; the rest waits for the next tick

  // Timing and sensors.
  void begin(Tick now) noexcept {
    started_ns_ = 0;
    if constexpr (HasStepClock<H>) started_ns_ = hal_.monotonic_ns();
    const Tick interval = timing_.begin(now);
    // The estimator integrates the true interval (it is stable for any); controllers integrate at most the
    // hard bound, past which the TIMING fault takes the lever down anyway.
    const Tick bounded = interval < config_.timing.fault_after ? interval : config_.timing.fault_after;
    dt_ = static_cast<double>(bounded) * kSecondsPerTick;
    telemetry_.sent_data = false;
    telemetry_.sent_refresh = false;
    read_sensors(now, static_cast<double>(interval) * kSecondsPerTick);
  }

  // Faults, control by state, the torque.
  void decide(Tick now) noexcept {
    supervisor_.boot_complete();
    switch (supervisor_.state()) {
      case LeverState::armed:
      case LeverState::fault:
        supervisor_.report(active_faults(now), now);
        break;
      case LeverState::homing:
        supervisor_.report(homing_faults(), now);
        break;
      case LeverState::init:
      case LeverState::disarmed:
        break;
    }
    apply_torque(control(now, dt_));
  }

  // The settings and the heartbeat, and the step's time on the board.
  void end(Tick now) noexcept {
    transmit_settings(now);
    if (now >= next_heartbeat_) {
      transmit_heartbeat();
      next_heartbeat_ = now + config_.heartbeat_period;
    }
    if constexpr (HasStepClock<H>) timing_.step_took(hal_.monotonic_ns() - started_ns_);
  }

  static LeverConfig with_role(LeverConfig c) noexcept {
    c.role = Role::kRole;
    return c;
  }

  // The faults that matter while the lever drives itself, without a peer: homing and armed alike.
  FaultBits homing_faults() const noexcept {
    FaultBits f = 0;
    if (decoder_.fault()) f |= bit(Fault::encoder);
    if (hal_.motor().driver_fault()) f |= bit(Fault::motor_driver);
    if (timing_.violated()) f |= bit(Fault::timing);
    if constexpr (HasBusFault<CanOf<H>>) {
      if (hal_.can().bus_fault()) f |= bit(Fault::can_bus);
    }
    return f;
  }

  void read_sensors(Tick now, double dt) noexcept {
    auto& encoder = hal_.encoder();
    std::int64_t counts = 0;
    if constexpr (EdgeEncoderPort<EncoderOf<H>>) {
      EncoderEdge edges[kMaxEdgesPerRead];
      // Bounded: at 10k edges/s a tick brings about 10 edges; a flood is cut at a few reads and waits.
      for (int read = 0; read < 8; ++read) {
        const EdgeDrain drained = encoder.drain_edges(edges, kMaxEdgesPerRead);
        decoder_.note_lost(drained.lost);
        for (std::size_t i = 0; i < drained.count; ++i) decoder_.feed(edges[i]);
        if (drained.count < kMaxEdgesPerRead) break;
      }
      counts = decoder_.counts();
      if (const auto index = decoder_.take_index()) index_raw_angle_ = position_.raw_angle_at(*index);
    } else {
      counts = counter_.update(encoder.read_counts());
    }
    position_.update(counts);
    if (decoder_.fault()) position_.invalidate();  // until homed again (or, absolute, until the fault clears)
    telemetry_.position_rad = position_.position();
    telemetry_.position_valid = position_.valid();
    const double raw_angle = position_.raw_angle();
    if (dt > 0.0) {
      telemetry_.velocity_rad_s = velocity_.update(raw_angle, dt);
      telemetry_.velocity_difference_rad_s = (raw_angle - previous_raw_angle_) / dt;
      if (config_.motion_velocity == MotionVelocity::adaptive_window)
        telemetry_.velocity_window_rad_s =
            window_.update(position_.counts(), now) * (position_.rad_per_count() / kSecondsPerTick);
    }
    previous_raw_angle_ = raw_angle;
    if (uses_gauge_) telemetry_.force_n = gauge_.update(hal_.force().latest(), now);
  }

  void receive_frames(Tick now) noexcept {
    protocol::CanFrame frame;
    for (std::size_t i = 0; i < kMaxFramesPerTick && hal_.can().receive(frame); ++i) handle_frame(frame, now);
  }

  void handle_frame(const protocol::CanFrame& frame, Tick now) noexcept {
    protocol::FrameAddress address;
    if (protocol::classify(frame.id, address) != protocol::DecodeError::none || address.pair != config_.pair)
      return;  // another pair's or another protocol's traffic on a shared bus
    protocol::DecodeError error = protocol::DecodeError::none;
    if (address.kind == Role::kReceives) {
      bool used = false;
      error = role_.receive(frame, now, used);
      if (error == protocol::DecodeError::none) {
        watchdog_.heard(now);
        if (!used) ++counters_.rx_stale;
      }
    } else if (address.kind == protocol::MessageKind::heartbeat) {
      protocol::HeartbeatMessage m;
      error = protocol::decode(frame, m, address);
      if (error == protocol::DecodeError::none && address.role == Role::kPeer) on_peer_heartbeat(m, now);
    } else if (address.kind == protocol::MessageKind::energy) {
      if (address.role != Role::kPeer) return;  // this lever's own kind, from another node
      protocol::EnergyMessage m;
      error = protocol::decode(frame, m, address);
      if (error == protocol::DecodeError::none) role_.passivity().receive(m);
    } else if (address.kind == protocol::MessageKind::command) {
      protocol::CommandMessage m;
      error = protocol::decode(frame, m, address);
      if (error == protocol::DecodeError::none && Role::addressed(m)) on_command(m, now);
    } else if (address.kind == protocol::MessageKind::settings) {
      return;  // for hosts: this lever follows its peer's settings by the mode on every data frame
    } else {
      return;  // this lever's own kind of data frame, from another node: not for it
    }
    if (error != protocol::DecodeError::none) {
      ++counters_.rx_rejected;
    } else {
      ++counters_.rx_frames;
    }
  }

  // The peer's state, as it says: a peer that was armed alongside this lever and no longer is (disarmed,
  // faulted, rebooted faster than the comms timeout) ends the pair's run; and whatever it sends next is a
  // new stream. "Alongside" is the arming handshake: the peer's heartbeat echoes this lever's current arming.
  // Without it, a pair re-armed over a link slower than the host's re-arm heard each other's heartbeats from
  // before the re-arm, "armed" and then "fault", and threw each other out again, re-arm after re-arm
  // (docs/can-protocol.md).
  void on_peer_heartbeat(const protocol::HeartbeatMessage& m, Tick now) noexcept {
    watchdog_.heard(now);
    if (supervisor_.armed()) {
      peer_arming_parity_ = m.arming_parity;
      peer_arming_known_ = true;
    }
    if (m.state == LeverState::armed) {
      const bool echoes_this_arming = m.peer_arming_known && m.peer_arming_parity == arming_parity();
      if (supervisor_.armed() && echoes_this_arming) peer_seen_armed_ = true;
      return;
    }
    role_.receiver().peer_stopped();
    if (supervisor_.armed() && peer_seen_armed_) peer_left_ = true;
  }

  // Every command is idempotent: a copy that finds the lever already where the command leads (armed, disarmed,
  // homed or homing, taring) changes nothing and is not counted as rejected, so a host may resend until the
  // heartbeat shows the state (lever-ctl, docs/can-protocol.md "Resending").
  void on_command(const protocol::CommandMessage& m, Tick now) noexcept {
    if (already_there(m.opcode)) return;
    bool accepted = true;
    switch (m.opcode) {
      case protocol::Opcode::arm:
        accepted = position_.valid() && supervisor_.arm(active_faults(now));
        if (accepted) on_armed();
        break;
      case protocol::Opcode::rearm:
        if (supervisor_.state() == LeverState::fault || supervisor_.state() == LeverState::disarmed) {
          // Conditions that only the fault itself kept alive restart with the re-arm. The encoder's count
          // stays invalid after an encoder fault (the lever must home again), unless it is absolute.
          clear_encoder_fault();
          saturated_ticks_ = 0;
        }
        accepted = position_.valid() && supervisor_.rearm(active_faults(now));
        if (accepted) on_armed();
        break;
      case protocol::Opcode::disarm:
        accepted = supervisor_.disarm();
        break;
      case protocol::Opcode::tare:
        accepted = !supervisor_.armed() && uses_gauge_;
        if (accepted) gauge_.start_tare();
        break;
      case protocol::Opcode::set_deadband: {
        const codec::Config<double> c = protocol::codec_settings(m);
        // Only the sending end of a direction owns its parameters; the receiving end follows the mode flag
        // carried by the data frames, which switches it at the same sample.
        accepted = codec::runs_at(c, 1.0 / kSecondsPerTick) && m.direction == Role::kSends;
        if (accepted) {
          role_.reconfigure(c);
          ++settings_changes_;  // a copy with the same values counts too: the host sees its command arrive
        }
        break;
      }
      case protocol::Opcode::home:
        if (homing_.needed() && supervisor_.state() == LeverState::disarmed) {
          clear_encoder_fault();
          position_.invalidate();  // whatever the count said, homing is what makes it mean something
        }
        accepted = homing_.needed() && supervisor_.home(homing_faults());
        if (accepted) {
          homing_.start(now, position_.raw_angle());
          index_raw_angle_.reset();
        }
        break;
    }
    if (!accepted) ++counters_.commands_rejected;
  }

  // A second arm or re-arm would restart the data streams and flip the arming parity; a second home would
  // throw away a homing's result, or restart one in progress; a second tare would restart the average.
  bool already_there(protocol::Opcode op) const noexcept {
    switch (op) {
      case protocol::Opcode::arm:
      case protocol::Opcode::rearm:
        return supervisor_.armed();
      case protocol::Opcode::disarm:
        return supervisor_.state() == LeverState::disarmed;
      case protocol::Opcode::home:
        return supervisor_.state() == LeverState::homing ||
               (supervisor_.state() == LeverState::disarmed && position_.valid());
      case protocol::Opcode::tare:
        return gauge_.taring();
      case protocol::Opcode::set_deadband:
        break;  // the same parameters again: the same configuration, and one more refresh frame
    }
    return false;
  }

  void clear_encoder_fault() noexcept {
    decoder_.clear_fault();
    if (!homing_.needed()) position_.reference(0.0, 0.0);  // absolute: the count is the position again
  }

  void on_armed() noexcept {
    role_.on_armed(telemetry_);
    ++armings_;
    peer_arming_known_ = false;
    peer_seen_armed_ = false;
    peer_left_ = false;
  }

  constexpr bool arming_parity() const noexcept { return (armings_ & 1u) != 0; }

  // Torque demand for this tick, by state.
  double control(Tick now, double dt) noexcept {
    telemetry_.remote.reset();
    switch (supervisor_.state()) {
      case LeverState::armed:
        return role_.control(now, dt, telemetry_);
      case LeverState::fault:
        return safe_behaviour(now);
      case LeverState::homing:
        return homing_step(now, dt);
      case LeverState::init:
      case LeverState::disarmed:
        break;
    }
    return 0.0;
  }

  double homing_step(Tick now, double dt) noexcept {
    const auto out = homing_.update(now, position_.raw_angle(), telemetry_.velocity_rad_s, index_raw_angle_, dt);
    index_raw_angle_.reset();
    switch (out.status) {
      case Homing::Status::done:
        position_.reference(homing_.reference_raw_angle(), config_.homing.home_position_rad);
        telemetry_.position_rad = position_.position();
        telemetry_.position_valid = true;
        supervisor_.homing_done();
        return 0.0;
      case Homing::Status::failed:
        supervisor_.report(bit(Fault::homing), now);
        return 0.0;
      case Homing::Status::running:
        break;
    }
    return out.torque_nm;
  }

  // The TOP holds the position where the fault struck, with limited torque, while the encoder and driver
  // can be trusted, then lets go. The HSI displays nothing.
  double safe_behaviour(Tick now) noexcept {
    if constexpr (Role::kHoldsOnFault) {
      if (now == supervisor_.fault_since()) hold_position_ = telemetry_.position_rad;
      const FaultBits latched = supervisor_.latched();
      const bool can_hold = position_.valid() && !has(latched, Fault::encoder) && !has(latched, Fault::motor_driver) &&
                            !has(latched, Fault::timing) && now - supervisor_.fault_since() < config_.safe_hold_ticks;
      if (!can_hold) return 0.0;
      const double torque = config_.position.kp * (hold_position_ - telemetry_.position_rad) -
                            config_.position.kd * telemetry_.velocity_rad_s;
      return clamp_torque(torque, config_.safe_hold_torque_nm);
    } else {
      (void)now;
      return 0.0;
    }
  }

  void apply_torque(double demand) noexcept {
    telemetry_.torque_demand_nm = demand;
    const bool over = !(demand == demand) || demand > config_.torque_limit_nm || demand < -config_.torque_limit_nm;
    saturated_ticks_ = supervisor_.armed() && over ? saturated_ticks_ + 1 : 0;
    const LeverState state = supervisor_.state();
    const bool active = (state == LeverState::fault || state == LeverState::homing) && demand != 0.0;
    const bool enable = supervisor_.armed() || active;
    telemetry_.torque_nm = enable ? clamp_torque(demand, config_.torque_limit_nm) : 0.0;
    telemetry_.motor_enabled = enable;
    hal_.motor().command({telemetry_.torque_nm, enable});
  }

  void transmit_data(Tick now) noexcept {
    const auto out = role_.transmit(now, telemetry_, config_.pair);
    if (!out) return;
    send(out->frame);
    ++counters_.data_sent;
    if (out->refresh) ++counters_.refresh_sent;
    telemetry_.sent_data = true;
    telemetry_.sent_refresh = out->refresh;
    telemetry_.sent_cause = out->cause;
    if (const auto energy = role_.passivity().frame(now, out->refresh)) {
      send(protocol::pack(*energy, config_.pair, Role::kRole));
      ++counters_.energy_sent;
    }
  }

  // On any change (a set_deadband taken, a tare started or done) in the step that made it, so the frame follows
  // the first data frame coded under a new setting; and every kSettingsPeriodMs for a host that missed it.
  void transmit_settings(Tick now) noexcept {
    const auto& c = role_.sender().config();
    protocol::SettingsMessage m;
    protocol::set_codec_settings(m, c);
    m.changes = static_cast<std::uint8_t>(settings_changes_ % protocol::kSettingsCountModulo);
    m.tares = static_cast<std::uint8_t>(gauge_.state().tares % protocol::kSettingsCountModulo);
    m.taring = gauge_.taring();
    if (now < next_settings_ && m == last_settings_) return;
    send(protocol::pack(m, config_.pair, Role::kRole));
    ++counters_.settings_sent;
    last_settings_ = m;
    next_settings_ = now + protocol::kSettingsPeriodMs;
  }

  void transmit_heartbeat() noexcept {
    const auto saturate = [](std::uint32_t v) { return static_cast<std::uint8_t>(v > 255 ? 255 : v); };
    protocol::HeartbeatMessage m;
    m.state = supervisor_.state();
    m.position_valid = position_.valid();
    m.arming_parity = arming_parity();
    m.peer_arming_parity = peer_arming_parity_;
    m.peer_arming_known = peer_arming_known_;
    m.faults = supervisor_.latched();
    m.last_data_seq = role_.sender().last_seq();
    m.seq_gaps = saturate(role_.receiver().sequence().missing());
    m.rejected_frames = saturate(counters_.rx_rejected);
    m.counter = heartbeat_counter_++;
    const std::uint32_t encoder_errors = decoder_.illegal_transitions() + decoder_.lost_edges();
    m.encoder_errors = saturate(encoder_errors < decoder_.lost_edges() ? UINT32_MAX : encoder_errors);
    send(protocol::pack(m, config_.pair, Role::kRole));
  }

  void send(const protocol::CanFrame& frame) noexcept {
    if (hal_.can().send(frame)) {
      ++counters_.tx_frames;
    } else {
      ++counters_.tx_dropped;
    }
  }

  H& hal_;
  LeverConfig config_;
  Supervisor supervisor_;
  QuadratureDecoder decoder_;
  CounterUnwrapper counter_;
  EncoderPosition position_;
  VelocityEstimator velocity_;
  AdaptiveWindowVelocity window_;
  StrainGauge gauge_;
  Homing homing_;
  StepTiming timing_;
  Role role_;
  Watchdog watchdog_;
  LeverTelemetry telemetry_;
  LeverCounters counters_;
  std::optional<double> index_raw_angle_;
  double previous_raw_angle_ = 0.0;  // for the backward difference
  double dt_ = 0.0;                  // this step's interval for the controllers, bounded
  std::uint64_t started_ns_ = 0;     // when this step began, on the board's step clock
  Tick next_heartbeat_ = 0;
  Tick next_settings_ = 0;
  protocol::SettingsMessage last_settings_{};
  std::uint32_t settings_changes_ = 0;  // set_deadband commands accepted
  Tick saturated_ticks_ = 0;
  double hold_position_ = 0.0;
  bool uses_gauge_;
  bool peer_seen_armed_ = false;  // in the handshake's sense: armed, and echoing this lever's current arming
  bool peer_left_ = false;
  std::uint32_t armings_ = 0;
  bool peer_arming_parity_ = false;  // what this lever echoes (HeartbeatMessage)
  bool peer_arming_known_ = false;
  std::uint8_t heartbeat_counter_ = 0;
};

template <LeverHal H>
using HsiLever = Lever<H, HsiRole>;
template <LeverHal H>
using TopLever = Lever<H, TopRole>;

}  // namespace lever::fw
