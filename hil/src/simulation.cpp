#include "lever/hil/simulation.hpp"

#include <chrono>
#include <cmath>
#include <memory>

#include "lever/fw/lever.hpp"
#include "lever/hil/can_bus.hpp"
#include "lever/hil/quadrature_encoder.hpp"

namespace lever::hil {
namespace {

constexpr Nanos kTick = 1'000'000;
constexpr Nanos kFirmwareTxDelay = 20'000;  // from step() to the frame in the controller's queue

struct SimMotor {
  fw::MotorCommand last;
  bool fault = false;
  void command(const fw::MotorCommand& c) { last = c; }
  bool driver_fault() const { return fault; }
};

struct SimCan {
  CanBus* bus = nullptr;
  CanBus::Node node = 0;
  const Nanos* now = nullptr;
  bool receive(protocol::CanFrame& f) { return bus->receive(node, f); }
  bool send(const protocol::CanFrame& f) { return bus->send(node, f, *now + kFirmwareTxDelay); }
};

// The board as the firmware core sees it, made of models.
struct SimHal {
  SimHal(double counts_per_rev, double angle, const StrainGaugeParams& gauge, std::uint64_t seed)
      : encoder_(counts_per_rev, angle), gauge_(gauge, seed) {}
  QuadratureEncoder encoder_;
  StrainGaugeModel gauge_;
  SimMotor motor_;
  SimCan can_;
  QuadratureEncoder& encoder() { return encoder_; }
  StrainGaugeModel& force() { return gauge_; }
  SimMotor& motor() { return motor_; }
  SimCan& can() { return can_; }
};
static_assert(fw::LeverHal<SimHal>);

// One lever with its plant and hardware, at one site.
struct LeverSite {
  LeverSite(const LeverPlantParams& plant_params, const fw::LeverConfig& fw_config, double angle,
            const StrainGaugeParams& gauge, std::uint64_t seed, CanBus& bus, const Nanos& now)
      : plant(plant_params, angle), hal(fw_config.counts_per_rev, angle, gauge, seed), lever(hal, fw_config) {
    hal.can_ = {&bus, bus.add_node(), &now};
  }
  LeverPlant plant;
  SimHal hal;
  fw::Lever<SimHal> lever;
  double torque() const { return hal.motor_.last.enable ? hal.motor_.last.torque_nm : 0.0; }
};

// A lever-bridge: every lever-protocol frame on its bus goes to the link, every datagram from the link onto
// its bus.
struct Bridge {
  CanBus* bus;
  CanBus::Node node;
  NetworkLink* outgoing;
  NetworkLink* incoming;
  Nanos latency;

  void pump(Nanos now) {
    protocol::CanFrame f;
    while (incoming->pop_arrived(now, f)) bus->send(node, f, now + latency);
    TimedFrame tf;
    protocol::FrameAddress address;
    while (bus->receive(node, tf))
      if (protocol::classify(tf.frame.id, address) == protocol::DecodeError::none)
        outgoing->send(tf.frame, tf.time + latency);
  }
};

bool safe_now(const fw::Lever<SimHal>& lever, const SimMotor& motor) {
  const auto& cfg = lever.config();
  if (cfg.role == protocol::Role::hsi) return !motor.last.enable || motor.last.torque_nm == 0.0;
  return std::fabs(motor.last.torque_nm) <= cfg.safe_hold_torque_nm;
}

void track_reaction(FaultReport::LeverReaction& r, const fw::Lever<SimHal>& lever, const SimMotor& motor, double t,
                    double injected) {
  if (t < injected) return;
  const auto state = lever.supervisor().state();
  if (!r.rearmed_at_s) r.max_torque_nm_during = std::max(r.max_torque_nm_during, std::fabs(motor.last.torque_nm));
  if (!r.fault_at_s && state == fw::LeverState::fault) {
    r.fault_at_s = t;
    r.latched = lever.supervisor().latched();
  }
  if (r.fault_at_s && !r.safe_at_s && safe_now(lever, motor)) r.safe_at_s = t;
  if (r.fault_at_s && !r.rearmed_at_s && state == fw::LeverState::armed) r.rearmed_at_s = t;
}

}  // namespace

fw::LeverConfig SimConfig::default_firmware(protocol::Role role) {
  fw::LeverConfig c;
  c.role = role;
  c.use_force_sensor = role == protocol::Role::top;
  return c;
}

SimResult run_simulation(const SimConfig& config) {
  const auto wall_start = std::chrono::steady_clock::now();
  Nanos now = 0;

  CanBus hsi_bus(config.bitrate), top_bus(config.bitrate);
  NetworkLink to_top(config.network, config.seed * 4 + 1), to_hsi(config.network, config.seed * 4 + 2);

  fw::LeverConfig hsi_fw = config.hsi_firmware, top_fw = config.top_firmware;
  hsi_fw.motion_codec = config.velocity_codec;
  top_fw.force_codec = config.force_codec;
  // Levers live at a fixed address: the core holds a reference to its HAL.
  auto hsi =
      std::make_unique<LeverSite>(config.hsi_plant, hsi_fw, 0.1, config.gauge, config.seed * 4 + 3, hsi_bus, now);
  auto top =
      std::make_unique<LeverSite>(config.top_plant, top_fw, 0.1, config.gauge, config.seed * 4 + 4, top_bus, now);
  const auto host = hsi_bus.add_node();  // the operator console at the HSI's site
  const Nanos latency = static_cast<Nanos>(config.bridge_latency_us * 1e3);
  Bridge bridge_hsi{&hsi_bus, hsi_bus.add_node(), &to_top, &to_hsi, latency};
  Bridge bridge_top{&top_bus, top_bus.add_node(), &to_hsi, &to_top, latency};

  HumanOperator op(config.operator_params, config.scenario, config.wall.angle, 0.1, config.seed * 4 + 5);
  hsi->plant.set_added_inertia(config.operator_params.hand_inertia);

  // The HSI's own gauge only matters to a closed-loop force display; its noise costs time otherwise.
  const bool hsi_gauge_used = hsi_fw.use_force_sensor && hsi_fw.display.closed_loop;
  SimResult result;
  for (const auto& f : config.faults) result.faults.push_back({f, {}, {}});
  const double top_arm = top_fw.display.lever_arm_m;
  const auto ticks = static_cast<fw::Tick>(std::llround(config.duration_s * 1000.0));
  const double dt = 1e-3 / config.substeps;
  double sq_position = 0, sq_force = 0, contact_force_sum = 0;
  std::uint64_t violations = 0, contact_ticks = 0;
  double fault_quiet_until = 0.0;  // the host waits for faults to end before re-arming

  for (fw::Tick tick = 1; tick <= ticks; ++tick) {
    const double t = static_cast<double>(tick) * 1e-3;
    now = static_cast<Nanos>(tick) * kTick;

    // Physics over the last millisecond, with the motor commands of the last step.
    for (int s = 0; s < config.substeps; ++s) {
      hsi->plant.advance(hsi->hal.motor_.last.torque_nm, hsi->hal.motor_.last.enable,
                         op.torque(hsi->plant.angle(), hsi->plant.speed()), dt);
      top->plant.advance(top->hal.motor_.last.torque_nm, top->hal.motor_.last.enable,
                         wall_torque(config.wall, top->plant.angle(), top->plant.speed()), dt);
      hsi->hal.encoder_.track(hsi->plant.angle());
      top->hal.encoder_.track(top->plant.angle());
    }
    const double contact = -wall_torque(config.wall, top->plant.angle(), top->plant.speed()) / top_arm;
    const double hand = op.hand_force(hsi->plant.angle(), hsi->plant.speed());

    // Faults in force during this tick.
    bool any_fault_active = false;
    to_top.set_down(false);
    to_hsi.set_down(false);
    to_top.set_burst_loss(0.0);
    to_hsi.set_burst_loss(0.0);
    to_top.set_extra_delay_ms(0.0);
    to_hsi.set_extra_delay_ms(0.0);
    for (const auto& f : config.faults) {
      const bool active = t >= f.start_s && t < f.start_s + f.duration_s;
      LeverSite& site = f.site == Site::hsi ? *hsi : *top;
      CanBus& bus = f.site == Site::hsi ? hsi_bus : top_bus;
      switch (f.kind) {
        case FaultKind::link_down:
          if (active) {
            to_top.set_down(true);
            to_hsi.set_down(true);
          }
          break;
        case FaultKind::burst_loss:
          if (active) {
            to_top.set_burst_loss(0.5);
            to_hsi.set_burst_loss(0.5);
          }
          break;
        case FaultKind::delay_step:
          if (active) {
            to_top.set_extra_delay_ms(f.value);
            to_hsi.set_extra_delay_ms(f.value);
          }
          break;
        case FaultKind::bus_off:
          bus.set_bus_off(site.hal.can_.node, active);
          break;
        case FaultKind::encoder_glitch:
          if (active) site.hal.encoder_.glitch();
          break;
        case FaultKind::gauge_stale:
          site.hal.gauge_.set_frozen(active);
          break;
        case FaultKind::gauge_saturated:
          site.hal.gauge_.set_saturated(active);
          break;
        case FaultKind::motor_fault:
          site.hal.motor_.fault = active;
          break;
      }
      if (active && f.kind != FaultKind::delay_step) any_fault_active = true;
      if (active) fault_quiet_until = std::max(fault_quiet_until, t + config.rearm_after_s);
    }

    top->hal.gauge_.update(contact, tick);
    if (hsi_gauge_used) hsi->hal.gauge_.update(hand, tick);

    // Frames: the link, then both buses up to now, then what the bridges picked up goes to the link.
    bridge_hsi.pump(now);
    bridge_top.pump(now);
    hsi_bus.advance_to(now);
    top_bus.advance_to(now);
    bridge_hsi.pump(now);
    bridge_top.pump(now);

    // The host arms both levers, and re-arms them once injected faults are over.
    if (tick % 100 == 0 && !any_fault_active && t >= fault_quiet_until) {
      const bool hsi_armed = hsi->lever.supervisor().armed(), top_armed = top->lever.supervisor().armed();
      if (!hsi_armed || !top_armed) {
        protocol::CommandMessage rearm;
        rearm.opcode = protocol::Opcode::rearm;
        rearm.to_hsi = !hsi_armed;
        rearm.to_top = !top_armed;
        hsi_bus.send(host, protocol::pack(rearm, hsi_fw.pair), now);
      }
    }

    op.update(tick, hand);
    hsi->lever.step(tick);
    top->lever.step(tick);

    // Measurements.
    const auto& ht = hsi->lever.telemetry();
    const auto& tt = top->lever.telemetry();
    const bool both_armed = hsi->lever.supervisor().armed() && top->lever.supervisor().armed();
    const double measured = tt.force_n.value_or(0.0);
    const double displayed = ht.remote.value_or(0.0);
    if (both_armed) {
      ++result.armed_ticks;
      result.motion_frames += ht.sent_data;
      result.force_frames += tt.sent_data;
      const double dp = top->plant.angle() - hsi->plant.angle();
      sq_position += dp * dp;
      const double df = displayed - measured;
      sq_force += df * df;
      if (std::fabs(df) > std::max(config.jnd * std::fabs(measured), config.jnd_absolute_n)) ++violations;
      if (contact > 0.0) {
        ++contact_ticks;
        contact_force_sum += contact;
      }
    }
    for (auto& r : result.faults) {
      track_reaction(r.hsi, hsi->lever, hsi->hal.motor_, t, r.spec.start_s);
      track_reaction(r.top, top->lever, top->hal.motor_, t, r.spec.start_s);
    }
    if (config.record_trace) {
      result.trace.push_back({t, hsi->plant.angle(), top->plant.angle(), ht.velocity_rad_s, tt.position_ref_rad,
                              contact, measured, displayed, hsi->torque(), top->torque(), hand, ht.sent_data,
                              tt.sent_data, static_cast<int>(hsi->lever.supervisor().state()),
                              static_cast<int>(top->lever.supervisor().state())});
    }
  }

  const double n = result.armed_ticks > 0 ? static_cast<double>(result.armed_ticks) : 1.0;
  result.velocity_packet_rate = static_cast<double>(result.motion_frames) / n;
  result.force_packet_rate = static_cast<double>(result.force_frames) / n;
  result.position_rmse_rad = std::sqrt(sq_position / n);
  result.force_rmse_n = std::sqrt(sq_force / n);
  result.force_jnd_violation = static_cast<double>(violations) / n;
  result.contact_share = static_cast<double>(contact_ticks) / n;
  result.mean_contact_force_n = contact_ticks > 0 ? contact_force_sum / static_cast<double>(contact_ticks) : 0.0;
  result.bus_load_hsi = hsi_bus.load();
  result.bus_load_top = top_bus.load();
  result.network_sent = to_top.stats().sent + to_hsi.stats().sent;
  result.network_lost = to_top.stats().lost + to_hsi.stats().lost;
  result.network_reordered = to_top.stats().reordered + to_hsi.stats().reordered;
  result.hsi_seq_gaps = hsi->lever.force_receiver().sequence().missing();
  result.top_seq_gaps = top->lever.motion_receiver().sequence().missing();
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.realtime_factor = config.duration_s / result.wall_time_s;
  return result;
}

}  // namespace lever::hil
