#include "lever/hil/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>

#include "lever/common/rng.hpp"
#include "lever/hil/can_bus.hpp"
#include "lever/hil/run_metrics.hpp"
#include "lever/hil/world.hpp"

namespace lever::hil {
namespace {

// A lever's dissipated energy over the run, from its passivity port's count since it last armed.
struct RunningTotal {
  double last_j = 0.0;
  double total_j = 0.0;
  void add(double since_armed_j) {
    total_j += since_armed_j >= last_j ? since_armed_j - last_j : since_armed_j;  // below the last: it re-armed
    last_j = since_armed_j;
  }
};

constexpr Nanos kTick = 1'000'000;
constexpr fw::Tick kHostPeriod = 100;       // the host looks at the levers every 100 ms
constexpr fw::Tick kPowerUpLimit = 30'000;  // homing and arming must be done by then

// One lever's controller and hardware, at one site (its mechanics are in the World). The firmware can be rebooted: it
// is rebuilt from its power-up state on the same hardware, with its own tick counting from 1 again.
template <typename LeverT>
struct LeverSite {
  LeverSite(const fw::LeverConfig& fw_config, double angle, const StrainGaugeParams& gauge, std::uint64_t seed,
            CanBus& bus, const Nanos& now)
      : hal(fw_config.counts_per_rev, angle, gauge, seed), config(fw_config) {
    hal.can_ = {&bus, bus.add_node(), &now};
    boot(1);
  }
  SimHal hal;
  fw::LeverConfig config;
  std::optional<LeverT> lever;
  fw::Tick boot_tick = 0;  // the simulation tick before the firmware's tick 1
  bool down = false;       // rebooting: silent, motor disabled (the driver's enable line defaults to off)
  bool skip = false;       // tick-late: not stepped, the motor keeps its last command
  std::uint64_t rearms_sent = 0;
  std::uint64_t rearms_at_fault = 0;
  fw::LeverState previous_state = fw::LeverState::init;

  void boot(fw::Tick tick) {
    fw::EncoderEdge discard[64];
    while (hal.encoder_.drain_edges(discard, 64).count > 0) {
    }  // the kernel's event queue does not survive a reboot
    lever.emplace(hal, config);
    boot_tick = tick - 1;
    hal.gauge_.set_clock_offset(boot_tick);  // a board's driver stamps readings on the firmware's clock
    down = false;
  }
  void go_down() {
    down = true;
    hal.motor_.last = {};
  }
  void step(fw::Tick tick) {
    if (!down && !skip) lever->step(tick - boot_tick);
  }
  double torque() const { return hal.motor_.last.enable ? hal.motor_.last.torque_nm : 0.0; }
  bool needs_homing() const {
    const auto s = lever->supervisor().state();
    return !lever->position().valid() && (s == fw::LeverState::disarmed || s == fw::LeverState::fault);
  }
  bool needs_arming() const {
    const auto s = lever->supervisor().state();
    return lever->position().valid() && (s == fw::LeverState::disarmed || s == fw::LeverState::fault);
  }
};

// A lever-bridge: every lever-protocol frame on its bus goes to the link, every datagram from the link onto
// its bus, each `latency` after it was received, by its own timestamp.
struct Bridge {
  CanBus* bus;
  CanBus::Node node;
  NetworkLink* outgoing;
  NetworkLink* incoming;
  Nanos latency;

  void pump(Nanos now) {
    TimedFrame tf;
    while (incoming->pop_arrived(now, tf)) bus->send(node, tf.frame, tf.time + latency);
    protocol::FrameAddress address;
    while (bus->receive(node, tf))
      if (protocol::classify(tf.frame.id, address) == protocol::DecodeError::none)
        outgoing->send(tf.frame, tf.time + latency);
  }
};

// The buses and bridges between two firmware ticks. Serviced every `step` up to `now`: a frame a bridge picks up
// in (s - step, s] is queued at s with its own time + latency > s, ahead of where the bus has run, so with
// step <= latency every frame's delay is exactly what the bus and network models give it (servicing only at
// ticks added up to two ticks to each hop: a frame took 3 ticks from one lever to the other).
struct Transport {
  CanBus* hsi_bus;
  CanBus* top_bus;  // the HSI's bus when both levers are on one site
  Bridge* bridges[2];
  Nanos step;

  void service(Nanos from, Nanos now) {
    for (Nanos s = from + step;; s += step) {
      if (s > now || quiet(now)) s = now;  // nothing on the buses, nothing arriving: nothing to do before now
      hsi_bus->advance_to(s);
      if (top_bus != hsi_bus) top_bus->advance_to(s);
      for (Bridge* b : bridges)
        if (b) b->pump(s);
      if (s == now) break;
    }
  }
  bool quiet(Nanos now) const {
    if (!hsi_bus->idle() || !top_bus->idle()) return false;
    for (const Bridge* b : bridges)
      if (b && b->incoming->arrives_by(now)) return false;
    return true;
  }
};

template <typename LeverT>
bool safe_now(const LeverT& lever, const SimMotor& motor) {
  if constexpr (!LeverT::role_type::kHoldsOnFault) {
    return !motor.last.enable || motor.last.torque_nm == 0.0;
  } else {
    return std::fabs(motor.last.torque_nm) <= lever.config().safe_hold_torque_nm;
  }
}

template <typename LeverT>
void track_reaction(FaultReport::LeverReaction& r, const LeverSite<LeverT>& site, double t, double injected) {
  if (t < injected) return;
  const auto& lever = *site.lever;
  const auto state = lever.supervisor().state();
  if (!r.rearmed_at_s)
    r.max_torque_nm_during = std::max(r.max_torque_nm_during, std::fabs(site.hal.motor_.last.torque_nm));
  if (!r.fault_at_s && state == fw::LeverState::fault) {
    r.fault_at_s = t;
    r.latched = lever.supervisor().latched();
  }
  if (r.fault_at_s && !r.safe_at_s && safe_now(lever, site.hal.motor_)) r.safe_at_s = t;
  if (r.fault_at_s && !r.rearmed_at_s && state == fw::LeverState::armed) r.rearmed_at_s = t;
}

// Armed again after a fault with no re-arm sent since the fault began: what the safety rules forbid.
template <typename LeverT>
void watch_rearm(LeverSite<LeverT>& site, bool& violated) {
  const auto state = site.lever->supervisor().state();
  if (state == fw::LeverState::fault && site.previous_state != fw::LeverState::fault)
    site.rearms_at_fault = site.rearms_sent;
  if (site.previous_state == fw::LeverState::fault && state == fw::LeverState::armed &&
      site.rearms_sent == site.rearms_at_fault)
    violated = true;
  site.previous_state = state;
}

}  // namespace

fw::LeverConfig SimConfig::default_firmware(protocol::Role role) {
  fw::LeverConfig c;
  c.role = role;
  c.use_force_sensor = role == protocol::Role::top;
  c.motion_velocity = fw::MotionVelocity::difference;  // the paper's chain (III-E)
  return c;
}

int nominal_one_way_delay_ticks(const SimConfig& config) {
  const double frame_ns = protocol::frame_bits_worst_case(8) * 1e9 / config.bitrate;
  const double ns = config.topology == Topology::one_site
                        ? frame_ns
                        : 2 * frame_ns + 2 * config.bridge_latency_us * 1e3 + config.network.delay_ms * 1e6;
  return static_cast<int>(std::ceil(ns / static_cast<double>(kTick)));
}

SimResult run_simulation(const SimConfig& config) {
  const auto wall_start = std::chrono::steady_clock::now();
  Nanos now = 0;

  if (!(config.bridge_latency_us >= 1.0))
    throw std::invalid_argument("HIL: a bridge takes at least 1 us from receiving a frame to sending it");
  const bool one_site = config.topology == Topology::one_site;
  CanBus hsi_bus(config.bitrate), top_site_bus(config.bitrate);
  CanBus& top_bus = one_site ? hsi_bus : top_site_bus;
  NetworkLink to_top(config.network, config.seed * 4 + 1), to_hsi(config.network, config.seed * 4 + 2);

  fw::LeverConfig hsi_fw = config.hsi_firmware, top_fw = config.top_firmware;
  hsi_fw.motion_codec = config.velocity_codec;
  top_fw.force_codec = config.force_codec;
  if (!config.gauge.valid()) throw std::invalid_argument("HIL: the strain gauge's parameters are out of range");
  calibrate_for(hsi_fw.gauge, config.gauge);
  calibrate_for(top_fw.gauge, config.gauge);
  // Power-up angles: anywhere in the working range with homing, the operator's start angle without.
  double hsi_angle = 0.1, top_angle = 0.1;
  if (config.homing) {
    Rng start(config.seed * 4 + 6);
    hsi_angle = start.uniform(-0.4, 0.25);
    top_angle = start.uniform(-0.4, 0.25);
  } else {
    hsi_fw.homing.method = fw::HomingMethod::absolute;
    top_fw.homing.method = fw::HomingMethod::absolute;
  }
  // Levers live at a fixed address: the core holds a reference to its HAL.
  auto hsi = std::make_unique<LeverSite<SimHsi>>(hsi_fw, hsi_angle, config.gauge, config.seed * 4 + 3, hsi_bus, now);
  auto top = std::make_unique<LeverSite<SimTop>>(top_fw, top_angle, config.gauge, config.seed * 4 + 4, top_bus, now);
  World world({config.scenario, config.hsi_plant, config.top_plant, config.wall, config.operator_params,
               config.substeps, config.seed * 4 + 5},
              hsi_angle, top_angle);
  const auto host = hsi_bus.add_node();  // the operator console at the HSI's site
  const Nanos latency = static_cast<Nanos>(config.bridge_latency_us * 1e3);
  std::optional<Bridge> bridge_hsi, bridge_top;
  if (!one_site) {
    bridge_hsi.emplace(Bridge{&hsi_bus, hsi_bus.add_node(), &to_top, &to_hsi, latency});
    bridge_top.emplace(Bridge{&top_bus, top_bus.add_node(), &to_hsi, &to_top, latency});
  }
  Transport transport{&hsi_bus,
                      &top_bus,
                      {bridge_hsi ? &*bridge_hsi : nullptr, bridge_top ? &*bridge_top : nullptr},
                      std::min<Nanos>(latency, 100'000)};

  auto send_command = [&](protocol::Opcode opcode, bool to_hsi_lever, bool to_top_lever) {
    if (!to_hsi_lever && !to_top_lever) return;
    protocol::CommandMessage m;
    m.opcode = opcode;
    m.to_hsi = to_hsi_lever;
    m.to_top = to_top_lever;
    hsi_bus.send(host, protocol::pack(m, hsi_fw.pair), now);
    if (opcode == protocol::Opcode::rearm) {
      hsi->rearms_sent += to_hsi_lever;
      top->rearms_sent += to_top_lever;
    }
  };
  // What the host does every 100 ms: home a lever whose position is unknown; once neither needs homing,
  // re-arm the ones that are not armed, so that the pair starts together.
  auto manage_levers = [&] {
    const bool hsi_home = hsi->needs_homing(), top_home = top->needs_homing();
    send_command(protocol::Opcode::home, hsi_home, top_home);
    const bool homing = hsi_home || top_home || hsi->lever->supervisor().state() == fw::LeverState::homing ||
                        top->lever->supervisor().state() == fw::LeverState::homing;
    if (!homing) send_command(protocol::Opcode::rearm, hsi->needs_arming(), top->needs_arming());
  };

  // The HSI's own gauge only matters to a closed-loop force display; its noise costs time otherwise.
  const bool hsi_gauge_used = hsi_fw.use_force_sensor && hsi_fw.display.closed_loop;
  SimResult result;
  for (const auto& f : config.faults) result.faults.push_back({f, {}, {}});
  std::vector<bool> rebooted(config.faults.size(), false);
  const auto scenario_ticks = static_cast<fw::Tick>(std::llround(config.duration_s * 1000.0));
  RunMetrics metrics(config.jnd, config.jnd_absolute_n);
  result.nominal_delay_ticks = nominal_one_way_delay_ticks(config);
  result.prefilter_delay_ms =
      config.force_codec.filter_hz > 0.0 ? 1e3 / (2.0 * std::numbers::pi * config.force_codec.filter_hz) : 0.0;
  // The TOP's measurements of the last nominal delay's ticks, for the distortion without the transport delay.
  RunningTotal dissipated[2];        // HSI, TOP
  bool was_armed[2] = {true, true};  // the scenario starts with both armed
  std::vector<std::optional<double>> measured_history(static_cast<std::size_t>(result.nominal_delay_ticks) + 1);
  double fault_quiet_until = 0.0;  // the host waits for faults to end before re-arming
  fw::Tick start = 0;              // the last tick before the scenario; 0 while powering up

  for (fw::Tick tick = 1; start == 0 || tick <= start + scenario_ticks; ++tick) {
    if (start == 0 && tick > kPowerUpLimit)
      throw std::runtime_error("HIL: the levers were not homed and armed within 30 s of power-up");
    const bool scenario = start != 0;
    const double t = scenario ? static_cast<double>(tick - start) * 1e-3 : -1e-3;
    now = static_cast<Nanos>(tick) * kTick;
    // The operator takes the handle once both levers are armed, and lets go while the HSI homes.
    world.set_hand_on(hsi->lever->supervisor().state() != fw::LeverState::homing, tick);

    // Physics over the last millisecond, with the motor commands of the last step.
    world.advance(hsi->hal.motor_.last, top->hal.motor_.last, [&] {
      hsi->hal.encoder_.track(world.hsi().angle());
      top->hal.encoder_.track(world.top().angle());
    });
    const double contact = world.contact_force();
    const double hand = world.hand_force();

    // Faults in force during this tick (scenario time).
    bool any_fault_active = false;
    to_top.set_down(false);
    to_hsi.set_down(false);
    to_top.set_burst_loss(0.0);
    to_hsi.set_burst_loss(0.0);
    to_top.set_extra_delay_ms(0.0);
    to_hsi.set_extra_delay_ms(0.0);
    hsi->skip = top->skip = false;
    for (std::size_t i = 0; scenario && i < config.faults.size(); ++i) {
      const auto& f = config.faults[i];
      const bool active = t >= f.start_s && t < f.start_s + f.duration_s;
      const bool at_hsi = f.site == Site::hsi;
      SimHal& hal = at_hsi ? hsi->hal : top->hal;
      CanBus& bus = at_hsi ? hsi_bus : top_bus;
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
          bus.set_bus_off(hal.can_.node, active);
          break;
        case FaultKind::encoder_glitch:
          if (active) hal.encoder_.glitch();
          break;
        case FaultKind::gauge_stale:
          hal.gauge_.set_frozen(active);
          break;
        case FaultKind::gauge_saturated:
          hal.gauge_.set_saturated(active);
          break;
        case FaultKind::motor_fault:
          hal.motor_.fault = active;
          break;
        case FaultKind::tick_late:
          if (active) (at_hsi ? hsi->skip : top->skip) = true;
          break;
        case FaultKind::reboot:
          if (!rebooted[i] && t >= f.start_s) {
            if (active) {
              at_hsi ? hsi->go_down() : top->go_down();
            } else {
              at_hsi ? hsi->boot(tick) : top->boot(tick);
              rebooted[i] = true;
            }
          }
          break;
      }
      const bool counts = active || (f.kind == FaultKind::reboot && t >= f.start_s && t < f.start_s + 1e-3);
      if (counts && f.kind != FaultKind::delay_step) any_fault_active = true;
      if (counts) fault_quiet_until = std::max(fault_quiet_until, t + config.rearm_after_s);
    }

    top->hal.gauge_.update(contact, tick);
    if (hsi_gauge_used) hsi->hal.gauge_.update(hand, tick);

    // Frames since the last tick, each at its own time.
    transport.service(now - kTick, now);

    // The host homes and arms both levers after power-up, and once injected faults are over re-homes and
    // re-arms the ones that need it.
    if (!scenario) {
      if (tick % kHostPeriod == 50) manage_levers();  // heartbeats have flowed for 50 ms by then
    } else if ((tick - start) % kHostPeriod == 0 && !any_fault_active && t >= fault_quiet_until) {
      manage_levers();
    }

    world.update_operator(tick, hand);
    hsi->step(tick);
    top->step(tick);

    const auto& hl = *hsi->lever;
    const auto& tl = *top->lever;
    const bool both_armed = hl.supervisor().armed() && tl.supervisor().armed();
    if (!scenario) {
      if (both_armed) {
        start = tick;
        result.homed_at_s = static_cast<double>(tick) * 1e-3;
        world.start_operator(tick);
      }
      if (config.observer) config.observer({t, tick, hl, tl, hsi->rearms_sent, top->rearms_sent});
      continue;
    }
    // Measurements.
    const auto& ht = hl.telemetry();
    const auto& tt = tl.telemetry();
    const double measured = tt.force_n.value_or(0.0);
    const double displayed = ht.remote.value_or(0.0);
    const auto slot = [&](fw::Tick k) -> std::optional<double>& {
      return measured_history[static_cast<std::size_t>(k) % measured_history.size()];
    };
    slot(tick) = both_armed ? tt.force_n : std::nullopt;
    // Every fault a lever latched while the scenario ran, injected or not: a delayed loop that trips a
    // lever's own protection (TORQUE_LIMIT, POSITION_LIMIT) has not survived the delay, whatever else it did.
    for (int i = 0; i < 2; ++i) {
      const auto& supervisor = i == 0 ? hl.supervisor() : tl.supervisor();
      const bool armed = supervisor.armed();
      auto& lever_faults = i == 0 ? result.hsi_lever_faults : result.top_lever_faults;
      if (was_armed[i] && !armed && supervisor.state() == fw::LeverState::fault) {
        ++lever_faults.count;
        lever_faults.bits |= supervisor.latched();
      }
      was_armed[i] = armed;
    }
    // The controllers' dissipated energy counts from each lever's arming; the run adds it up across re-arms.
    // It is read from the ports themselves: the telemetry holds it only on the ticks the controllers run.
    dissipated[0].add(hl.role().passivity().state().dissipated_j);
    dissipated[1].add(tl.role().passivity().state().dissipated_j);
    if (both_armed) {
      result.refresh_frames += ht.sent_refresh + tt.sent_refresh;
      result.hsi_min_observed_energy_j = std::min(result.hsi_min_observed_energy_j, ht.observed_energy_j);
      result.top_min_observed_energy_j = std::min(result.top_min_observed_energy_j, tt.observed_energy_j);
      metrics.add_armed_tick(ht.sent_data, tt.sent_data, world.top().angle() - world.hsi().angle(), displayed, measured,
                             contact);
      const auto& sender = tl.role().sender().codec_sender();
      const auto& delayed = slot(tick + 1);  // the oldest entry: nominal_delay_ticks ago
      if (tt.force_n && delayed && ht.remote && !sender.model().empty()) {
        const double lossless = sender.model().at(static_cast<double>(tick - top->boot_tick))[0];
        const double filtered = sender.prefilter().enabled() ? sender.prefilter().output()[0] : measured;
        metrics.add_force_causes(displayed, *delayed, lossless, filtered, measured);
      }
    }
    for (auto& r : result.faults) {
      track_reaction(r.hsi, *hsi, t, r.spec.start_s);
      track_reaction(r.top, *top, t, r.spec.start_s);
    }
    bool hsi_bad = false, top_bad = false;
    watch_rearm(*hsi, hsi_bad);
    watch_rearm(*top, top_bad);
    for (auto& r : result.faults) {
      r.hsi.armed_without_rearm = r.hsi.armed_without_rearm || hsi_bad;
      r.top.armed_without_rearm = r.top.armed_without_rearm || top_bad;
    }
    if (config.record_trace) {
      const TraceRow row{t,
                         world.hsi().angle(),
                         world.top().angle(),
                         ht.velocity_rad_s,
                         tt.position_ref_rad,
                         contact,
                         measured,
                         displayed,
                         hsi->torque(),
                         top->torque(),
                         hand,
                         ht.sent_data,
                         tt.sent_data,
                         static_cast<int>(hl.supervisor().state()),
                         static_cast<int>(tl.supervisor().state())};
      if (config.trace_sink) {
        config.trace_sink(row);
      } else {
        result.trace.push_back(row);
      }
    }
    if (config.observer) config.observer({t, tick, hl, tl, hsi->rearms_sent, top->rearms_sent});
  }

  const auto& hl = *hsi->lever;
  const auto& tl = *top->lever;
  metrics.finish(result);
  result.bus_load_hsi = hsi_bus.load();
  result.bus_load_top = top_bus.load();
  result.network_sent = to_top.stats().sent + to_hsi.stats().sent;
  result.network_lost = to_top.stats().lost + to_hsi.stats().lost;
  result.network_reordered = to_top.stats().reordered + to_hsi.stats().reordered;
  result.hsi_dissipated_energy_j = dissipated[0].total_j;
  result.top_dissipated_energy_j = dissipated[1].total_j;
  result.energy_frames = hl.counters().energy_sent + tl.counters().energy_sent;
  result.hsi_seq_gaps = hl.role().receiver().sequence().missing();
  result.top_seq_gaps = tl.role().receiver().sequence().missing();
  result.hsi_overruns = hl.timing().stats().overruns;
  result.top_overruns = tl.timing().stats().overruns;
  result.hsi_edges_lost = hsi->hal.encoder_.overflowed();
  result.top_edges_lost = top->hal.encoder_.overflowed();
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.realtime_factor = config.duration_s / result.wall_time_s;
  return result;
}

}  // namespace lever::hil
