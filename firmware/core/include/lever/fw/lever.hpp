#pragma once
// The lever application for both roles, advanced by step(now) once per 1 ms tick. No heap, no exceptions,
// no OS: everything it touches comes through the HAL (hal.hpp).
//
// Per tick: read sensors -> take frames from the bus -> find faults -> control by role and state -> clamp
// torque -> command the motor -> transmit data and heartbeat.
#include <cstdint>
#include <numbers>
#include <optional>

#include "lever/fw/controllers.hpp"
#include "lever/fw/data_channel.hpp"
#include "lever/fw/faults.hpp"
#include "lever/fw/hal.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/fw/link.hpp"
#include "lever/fw/quadrature_decoder.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/fw/supervisor.hpp"
#include "lever/fw/velocity_estimator.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

struct LeverCounters {
  std::uint32_t rx_frames = 0;    // frames for this pair, decoded
  std::uint32_t rx_rejected = 0;  // frames for this pair that failed to decode
  std::uint32_t rx_stale = 0;     // duplicate or reordered data frames, not used
  std::uint32_t tx_frames = 0;
  std::uint32_t tx_dropped = 0;         // the CAN queue was full
  std::uint32_t data_sent = 0;          // deadband data frames sent
  std::uint32_t commands_rejected = 0;  // commands refused by the supervisor or with invalid parameters
};

struct LeverTelemetry {
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  std::optional<double> force_n;  // own strain gauge, calibrated; empty when stale
  std::optional<double> remote;   // reconstructed peer value: HSI velocity at the TOP, force at the HSI
  double position_ref_rad = 0.0;  // TOP tracking reference
  double velocity_ref_rad_s = 0.0;
  double torque_demand_nm = 0.0;  // before the limit
  double torque_nm = 0.0;         // commanded
  bool motor_enabled = false;
  bool sent_data = false;  // this tick
};

template <LeverHal H>
class Lever {
 public:
  using MotionSender = DataSender<std::int16_t>;
  using ForceSender = DataSender<std::int32_t>;

  Lever(H& hal, const LeverConfig& config) noexcept
      : hal_(hal),
        config_(config),
        decoder_(config.decoder),
        velocity_(config.velocity),
        gauge_(config.gauge),
        position_ctrl_(config.position),
        display_(config.display),
        motion_tx_(config.motion_codec, velocity_quantizer(), config.refresh_period),
        force_tx_(config.force_codec, force_quantizer(), config.refresh_period),
        motion_rx_(velocity_quantizer()),
        force_rx_(force_quantizer()) {}

  void step(Tick now) noexcept {
    const double dt = started_ && now > last_step_ ? static_cast<double>(now - last_step_) * kSecondsPerTick : 0.0;
    started_ = true;
    last_step_ = now;
    telemetry_.sent_data = false;

    read_sensors(now, dt);
    receive_frames(now);
    supervisor_.boot_complete();
    if (supervisor_.state() == LeverState::armed || supervisor_.state() == LeverState::fault) {
      supervisor_.report(active_faults(now), now);
    }
    const double demand = control(now, dt);
    apply_torque(demand);
    if (supervisor_.armed()) transmit_data(now);
    if (now >= next_heartbeat_) {
      transmit_heartbeat();
      next_heartbeat_ = now + config_.heartbeat_period;
    }
  }

  const LeverConfig& config() const noexcept { return config_; }
  const Supervisor& supervisor() const noexcept { return supervisor_; }
  const LeverTelemetry& telemetry() const noexcept { return telemetry_; }
  const LeverCounters& counters() const noexcept { return counters_; }
  const QuadratureDecoder& decoder() const noexcept { return decoder_; }
  const StrainGauge& gauge() const noexcept { return gauge_; }
  const MotionSender& motion_sender() const noexcept { return motion_tx_; }
  const ForceSender& force_sender() const noexcept { return force_tx_; }
  const DataReceiver<std::int16_t>& motion_receiver() const noexcept { return motion_rx_; }
  const DataReceiver<std::int32_t>& force_receiver() const noexcept { return force_rx_; }

  // Faults whose conditions hold now (what arm and re-arm check).
  FaultBits active_faults(Tick now) const noexcept {
    FaultBits f = 0;
    if (watchdog_.silent(now, config_.comms_timeout)) f |= bit(Fault::comms_timeout);
    if (decoder_.fault()) f |= bit(Fault::encoder);
    if (uses_gauge()) {
      if (gauge_.state().stale) f |= bit(Fault::force_stale);
      if (gauge_.state().saturated) f |= bit(Fault::force_saturated);
    }
    if (hal_.motor().driver_fault()) f |= bit(Fault::motor_driver);
    if (saturated_ticks_ > config_.torque_saturation_ticks) f |= bit(Fault::torque_limit);
    if (telemetry_.position_rad < config_.position_min_rad || telemetry_.position_rad > config_.position_max_rad)
      f |= bit(Fault::position_limit);
    return f;
  }

 private:
  static constexpr std::size_t kMaxEdgesPerRead = 64;
  static constexpr std::size_t kMaxFramesPerTick = 16;  // bounds the loop; the rest waits for the next tick

  static constexpr WireQuantizer<std::int16_t> velocity_quantizer() noexcept { return {protocol::kVelocityLsb}; }
  static constexpr WireQuantizer<std::int32_t> force_quantizer() noexcept {
    return {protocol::kForceLsb, protocol::kForceCodeMin, protocol::kForceCodeMax};
  }
  static constexpr WireQuantizer<std::int16_t> position_quantizer() noexcept { return {protocol::kPositionLsbRad}; }

  bool is_hsi() const noexcept { return config_.role == protocol::Role::hsi; }
  // Two refresh periods without data: the sender has stopped, not merely stayed inside its deadband.
  Tick stale_after() const noexcept { return 2 * config_.refresh_period; }
  bool uses_gauge() const noexcept { return !is_hsi() || (config_.use_force_sensor && config_.display.closed_loop); }

  void read_sensors(Tick now, double dt) noexcept {
    auto& encoder = hal_.encoder();
    std::int32_t counts = 0;
    if constexpr (EdgeEncoderPort<EncoderOf<H>>) {
      AbState edges[kMaxEdgesPerRead];
      // Bounded: at 10k edges/s a tick brings about 10 edges; a flood is cut at a few reads.
      for (int read = 0; read < 8; ++read) {
        const std::size_t n = encoder.drain_edges(edges, kMaxEdgesPerRead);
        for (std::size_t i = 0; i < n; ++i) decoder_.feed(edges[i]);
        if (n < kMaxEdgesPerRead) break;
      }
      counts = decoder_.counts();
    } else {
      counts = encoder.read_counts();
    }
    telemetry_.position_rad = static_cast<double>(counts) * (2.0 * std::numbers::pi / config_.counts_per_rev);
    if (dt > 0.0) telemetry_.velocity_rad_s = velocity_.update(telemetry_.position_rad, dt);
    if (uses_gauge()) telemetry_.force_n = gauge_.update(hal_.force().latest(), now);
  }

  void receive_frames(Tick now) noexcept {
    protocol::CanFrame frame;
    for (std::size_t i = 0; i < kMaxFramesPerTick && hal_.can().receive(frame); ++i) handle_frame(frame, now);
  }

  void handle_frame(const protocol::CanFrame& frame, Tick now) noexcept {
    protocol::FrameAddress address;
    if (protocol::classify(frame.id, address) != protocol::DecodeError::none || address.pair != config_.pair)
      return;  // another pair's or another protocol's traffic on a shared bus
    const protocol::Role peer = is_hsi() ? protocol::Role::top : protocol::Role::hsi;
    protocol::DecodeError error = protocol::DecodeError::none;
    switch (address.kind) {
      case protocol::MessageKind::motion: {
        protocol::MotionMessage m;
        error = protocol::decode(frame, m, address);
        if (error == protocol::DecodeError::none && !is_hsi()) on_motion(m, now);
        break;
      }
      case protocol::MessageKind::force: {
        protocol::ForceMessage m;
        error = protocol::decode(frame, m, address);
        if (error == protocol::DecodeError::none && is_hsi()) on_force(m, now);
        break;
      }
      case protocol::MessageKind::heartbeat: {
        protocol::HeartbeatMessage m;
        error = protocol::decode(frame, m, address);
        if (error == protocol::DecodeError::none && address.role == peer) watchdog_.heard(now);
        break;
      }
      case protocol::MessageKind::command: {
        protocol::CommandMessage m;
        error = protocol::decode(frame, m, address);
        if (error == protocol::DecodeError::none) on_command(m, now);
        break;
      }
    }
    if (error != protocol::DecodeError::none) {
      ++counters_.rx_rejected;
    } else {
      ++counters_.rx_frames;
    }
  }

  void on_motion(const protocol::MotionMessage& m, Tick now) noexcept {
    watchdog_.heard(now);
    if (!motion_rx_.accept(now, m.tick, m.seq, m.flags.mode, m.velocity)) {
      ++counters_.rx_stale;
      return;
    }
    // The position rides on every velocity frame and resets the integrated reference (paper section III-A).
    telemetry_.position_ref_rad = position_quantizer().decode(m.position);
    have_motion_ = true;
  }

  void on_force(const protocol::ForceMessage& m, Tick now) noexcept {
    watchdog_.heard(now);
    if (!force_rx_.accept(now, m.tick, m.seq, m.flags.mode, m.force)) ++counters_.rx_stale;
  }

  void on_command(const protocol::CommandMessage& m, Tick now) noexcept {
    if (!(is_hsi() ? m.to_hsi : m.to_top)) return;
    bool accepted = true;
    switch (m.opcode) {
      case protocol::Opcode::arm:
        accepted = supervisor_.arm(active_faults(now));
        if (accepted) on_armed();
        break;
      case protocol::Opcode::rearm:
        if (supervisor_.state() == LeverState::fault || supervisor_.state() == LeverState::disarmed) {
          // Conditions that only the fault itself kept alive restart with the re-arm.
          decoder_.clear_fault();
          saturated_ticks_ = 0;
        }
        accepted = supervisor_.rearm(active_faults(now));
        if (accepted) on_armed();
        break;
      case protocol::Opcode::disarm:
        accepted = supervisor_.disarm();
        break;
      case protocol::Opcode::tare:
        accepted = !supervisor_.armed() && uses_gauge();
        if (accepted) gauge_.start_tare();
        break;
      case protocol::Opcode::set_deadband: {
        const codec::Config<double> c{m.mode, m.p * protocol::kPLsb, m.floor * protocol::kFloorLsb,
                                      m.filter_hz * protocol::kFilterHzLsb};
        accepted = codec::is_valid(c);
        // Only the sending end of a direction owns its parameters; the receiving end follows the mode flag
        // carried by the data frames, which switches it at the same sample.
        if (accepted && m.direction == protocol::Direction::motion && is_hsi()) motion_tx_.reconfigure(c);
        if (accepted && m.direction == protocol::Direction::force && !is_hsi()) force_tx_.reconfigure(c);
        break;
      }
    }
    if (!accepted) ++counters_.commands_rejected;
  }

  void on_armed() noexcept {
    motion_tx_.restart();
    force_tx_.restart();
    display_.reset();
    // Until the HSI's motion arrives, the TOP holds where it is.
    telemetry_.position_ref_rad = telemetry_.position_rad;
    telemetry_.velocity_ref_rad_s = 0.0;
    have_motion_ = false;
  }

  // Torque demand for this tick, by role and state.
  double control(Tick now, double dt) noexcept {
    telemetry_.remote.reset();
    if (supervisor_.state() == LeverState::fault) return safe_behaviour(now);
    if (!supervisor_.armed()) return 0.0;

    if (is_hsi()) {
      telemetry_.remote = force_rx_.value_at(now, stale_after());
      const double remote_force = telemetry_.remote.value_or(0.0);
      const double* own = telemetry_.force_n ? &*telemetry_.force_n : nullptr;
      return display_.update(remote_force, own, telemetry_.velocity_rad_s, dt);
    }
    if (have_motion_) {
      // A stale stream leaves the reference where it was: the TOP holds instead of integrating old motion.
      telemetry_.remote = motion_rx_.value_at(now, stale_after());
      telemetry_.velocity_ref_rad_s = telemetry_.remote.value_or(0.0);
      if (now != motion_rx_.last_arrival()) telemetry_.position_ref_rad += telemetry_.velocity_ref_rad_s * dt;
    }
    return position_ctrl_.update(telemetry_.position_ref_rad, telemetry_.velocity_ref_rad_s, telemetry_.position_rad,
                                 telemetry_.velocity_rad_s);
  }

  // TOP: hold the position where the fault struck, with limited torque, while the encoder and driver can be
  // trusted, then let go. HSI: display nothing.
  double safe_behaviour(Tick now) noexcept {
    if (now == supervisor_.fault_since()) hold_position_ = telemetry_.position_rad;
    const FaultBits latched = supervisor_.latched();
    const bool can_hold = !is_hsi() && !has(latched, Fault::encoder) && !has(latched, Fault::motor_driver) &&
                          now - supervisor_.fault_since() < config_.safe_hold_ticks;
    if (!can_hold) return 0.0;
    const double torque = config_.position.kp * (hold_position_ - telemetry_.position_rad) -
                          config_.position.kd * telemetry_.velocity_rad_s;
    return clamp_torque(torque, config_.safe_hold_torque_nm);
  }

  void apply_torque(double demand) noexcept {
    telemetry_.torque_demand_nm = demand;
    const bool over = !(demand == demand) || demand > config_.torque_limit_nm || demand < -config_.torque_limit_nm;
    saturated_ticks_ = supervisor_.armed() && over ? saturated_ticks_ + 1 : 0;
    const bool holding = supervisor_.state() == LeverState::fault && demand != 0.0;
    const bool enable = supervisor_.armed() || holding;
    telemetry_.torque_nm = enable ? clamp_torque(demand, config_.torque_limit_nm) : 0.0;
    telemetry_.motor_enabled = enable;
    hal_.motor().command({telemetry_.torque_nm, enable});
  }

  void transmit_data(Tick now) noexcept {
    const auto tick16 = static_cast<std::uint16_t>(now & 0xFFFFu);
    if (is_hsi()) {
      const auto out = motion_tx_.offer(now, telemetry_.velocity_rad_s);
      if (!out.send) return;
      bool position_saturated = false;
      protocol::MotionMessage m;
      m.position = position_quantizer().encode(telemetry_.position_rad, position_saturated);
      m.velocity = out.code;
      m.tick = tick16;
      m.seq = out.seq;
      m.flags = {position_saturated, out.saturated, out.refresh, out.mode};
      send(protocol::pack(m, config_.pair));
    } else {
      if (!telemetry_.force_n) return;  // stale gauge: the supervisor is already taking the lever down
      const auto out = force_tx_.offer(now, *telemetry_.force_n);
      if (!out.send) return;
      protocol::ForceMessage m;
      m.force = out.code;
      m.tick = tick16;
      m.seq = out.seq;
      m.flags = {out.saturated, false, out.refresh, out.mode};
      send(protocol::pack(m, config_.pair));
    }
    ++counters_.data_sent;
    telemetry_.sent_data = true;
  }

  void transmit_heartbeat() noexcept {
    const auto saturate = [](std::uint32_t v) { return static_cast<std::uint8_t>(v > 255 ? 255 : v); };
    const auto& rx_seq = is_hsi() ? force_rx_.sequence() : motion_rx_.sequence();
    protocol::HeartbeatMessage m;
    m.state = supervisor_.state();
    m.faults = supervisor_.latched();
    m.last_data_seq = is_hsi() ? motion_tx_.last_seq() : force_tx_.last_seq();
    m.seq_gaps = saturate(rx_seq.missing());
    m.rejected_frames = saturate(counters_.rx_rejected);
    m.counter = heartbeat_counter_++;
    m.encoder_errors = saturate(decoder_.illegal_transitions());
    send(protocol::pack(m, config_.pair, config_.role));
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
  VelocityEstimator velocity_;
  StrainGauge gauge_;
  PositionController position_ctrl_;
  ForceDisplay display_;
  MotionSender motion_tx_;
  ForceSender force_tx_;
  DataReceiver<std::int16_t> motion_rx_;
  DataReceiver<std::int32_t> force_rx_;
  Watchdog watchdog_;
  LeverTelemetry telemetry_;
  LeverCounters counters_;
  Tick last_step_ = 0;
  Tick next_heartbeat_ = 0;
  Tick saturated_ticks_ = 0;
  double hold_position_ = 0.0;
  bool started_ = false;
  bool have_motion_ = false;
  std::uint8_t heartbeat_counter_ = 0;
};

}  // namespace lever::fw
