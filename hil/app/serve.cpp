#include "serve.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <optional>
#include <thread>

#include "bus_watch.hpp"
#include "lever/app/fw_config.hpp"
#include "lever/app/stats_line.hpp"
#include "lever/common/rng.hpp"
#include "lever/hil/devices/encoder_lines.hpp"
#include "lever/hil/devices/gauge_server.hpp"
#include "lever/hil/devices/motor_readback.hpp"
#include "lever/hil/run_metrics.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/strain_gauge_model.hpp"
#include "lever/hil/world.hpp"
#include "lever/program/exit_codes.hpp"
#include "lever/program/output_file.hpp"
#include "lever/protocol/faults.hpp"
#include "report.hpp"

namespace lever::hil {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kRuntimeFailure = program::kRuntimeFailure;
constexpr int kBadInput = program::kBadInput;
// A lever heard within this is alive; lever-fw's heartbeat period is 25 ms by default, and the guest's
// emulated clock stretches it.
constexpr std::int64_t kHeardWindowMs = 250;
// The world that falls further behind the wall clock than this stops catching up and slips (counted): a burst
// of physics steps to catch up seconds would only show the levers a jump.
constexpr std::int64_t kMaxCatchUpMs = 50;

// One lever's devices, as the world drives and reads them.
struct LeverDevices {
  std::optional<devices::EncoderLines> encoder;
  std::optional<devices::MotorReadback> motor;
  std::optional<devices::GaugeServer> gauge;  // only a lever that reads its gauge has one
  double counts_per_radian = 0.0;
  std::int64_t count_origin = 0;  // the count at power-up: an incremental encoder's count starts anywhere

  std::int64_t count_at(double angle) const {
    return static_cast<std::int64_t>(std::floor(angle * counts_per_radian)) - count_origin;
  }
};

std::optional<LeverDevices> open_devices(const app::FwConfig& config, double angle, double max_edge_rate_hz) {
  LeverDevices d;
  const bool hsi = config.lever.role == protocol::Role::hsi;
  const char* who = hsi ? "HSI" : "TOP";
  d.counts_per_radian = config.lever.counts_per_rev / (2.0 * std::numbers::pi);
  d.count_origin = static_cast<std::int64_t>(std::floor(angle * d.counts_per_radian));
  const auto encoder_config = app::encoder_config(config.board);
  devices::EncoderLinesOptions options;
  options.max_edge_rate_hz = max_edge_rate_hz;
  // The index mark sits at angle 0, as the in-process HIL's encoder has it.
  if (encoder_config.line_z) options.index_at_count = -d.count_origin;
  auto encoder = devices::EncoderLines::open(encoder_config, options);
  if (!encoder) {
    fmt::print(stderr, "lever-hil serve: {} encoder: {}\n", who, encoder.error().message);
    return std::nullopt;
  }
  d.encoder = std::move(encoder).value();
  auto motor = devices::MotorReadback::open(app::motor_config(config.board));
  if (!motor) {
    fmt::print(stderr, "lever-hil serve: {} motor: {}\n", who, motor.error().message);
    return std::nullopt;
  }
  d.motor = std::move(motor).value();
  const bool reads_gauge = !hsi || (config.lever.use_force_sensor && config.lever.display.closed_loop);
  if (reads_gauge) {
    auto gauge = devices::GaugeServer::open(app::gauge_config(config.board));
    if (!gauge) {
      fmt::print(stderr, "lever-hil serve: {} strain gauge: {}\n", who, gauge.error().message);
      return std::nullopt;
    }
    d.gauge = std::move(gauge).value();
  }
  fmt::print(stderr, "lever-hil serve: {} lever: encoder {}; motor {}; gauge {}\n", who, d.encoder->description(),
             d.motor->description(), d.gauge ? d.gauge->description() : std::string("none (not read)"));
  return d;
}

std::string state_name(const WatchedLever& l) { return l.heartbeat ? app::state_name(l.heartbeat->state) : "silent"; }

std::string faults_text(const WatchedLever& l) {
  if (!l.heartbeat || l.heartbeat->faults == 0) return "";
  std::string names;
  for (const auto bit : protocol::kAllFaults)
    if (protocol::has(l.heartbeat->faults, bit)) names += (names.empty() ? " [" : "+") + std::string(name(bit));
  return names + "]";
}

int state_number(const WatchedLever& l) { return l.heartbeat ? static_cast<int>(l.heartbeat->state) : -1; }

// What serve measures, beyond what SimResult holds.
struct ServeExtras {
  double max_position_error_rad = 0.0;
  double hsi_torque_in_contact_sum = 0.0;  // N m, HSI motor torque while the TOP touches the wall
  double max_displayed_force_n = 0.0;
  std::uint64_t slips = 0;      // the world fell behind the wall clock by more than kMaxCatchUpMs
  std::int64_t max_lag_ms = 0;  // the furthest it was behind
  std::uint64_t hsi_silent_ms = 0, top_silent_ms = 0;  // after the start: no heartbeat within the window
};

}  // namespace

int run_serve(const ServeOptions& o, const std::atomic<bool>& stop) {
  auto hsi_loaded = app::load_fw_config(o.hsi_config);
  auto top_loaded = app::load_fw_config(o.top_config);
  for (const auto* loaded : {&hsi_loaded, &top_loaded}) {
    if (!loaded->error.empty()) {
      fmt::print(stderr, "lever-hil serve: {}\n", loaded->error);
      return kBadInput;
    }
  }
  const app::FwConfig& hsi_config = hsi_loaded.config;
  const app::FwConfig& top_config = top_loaded.config;
  if (hsi_config.lever.role != protocol::Role::hsi || top_config.lever.role != protocol::Role::top) {
    fmt::print(stderr, "lever-hil serve: {} must configure an HSI lever and {} a TOP lever (lever.role)\n",
               o.hsi_config, o.top_config);
    return kBadInput;
  }
  if (hsi_config.lever.pair != top_config.lever.pair) {
    fmt::print(stderr, "lever-hil serve: the levers are of different pairs ({} and {}; lever.pair)\n",
               hsi_config.lever.pair, top_config.lever.pair);
    return kBadInput;
  }

  // Checked before any device is opened. Written as the run goes and renamed into place when it ends (by its duration
  // or a signal).
  std::optional<program::OutputFile> trace;
  if (!o.trace.empty()) {
    trace.emplace(o.trace, "--trace");
    trace->write(trace_csv_header());
  }

  // The same physical world as lever-hil run: power-up angles drawn the same way, the same models.
  SimConfig sim;
  sim.scenario = o.scenario;
  sim.duration_s = o.duration_s;
  sim.seed = o.seed;
  sim.velocity_codec = hsi_config.lever.motion_codec;
  sim.force_codec = top_config.lever.force_codec;
  sim.hsi_firmware = hsi_config.lever;
  sim.top_firmware = top_config.lever;
  Rng start(o.seed * 4 + 6);
  const double hsi_angle = start.uniform(-0.4, 0.25);
  const double top_angle = start.uniform(-0.4, 0.25);
  World world({o.scenario, sim.hsi_plant, sim.top_plant, sim.wall, sim.operator_params, sim.substeps, o.seed * 4 + 5},
              hsi_angle, top_angle);
  StrainGaugeModel top_gauge(sim.gauge, o.seed * 4 + 4), hsi_gauge(sim.gauge, o.seed * 4 + 3);

  auto hsi = open_devices(hsi_config, hsi_angle, o.max_edge_rate_hz);
  if (!hsi) return kRuntimeFailure;
  auto top = open_devices(top_config, top_angle, o.max_edge_rate_hz);
  if (!top) return kRuntimeFailure;
  auto watch_result =
      BusWatch::open(hsi_config.board.can_interface, top_config.board.can_interface, hsi_config.lever.pair);
  if (!watch_result) {
    fmt::print(stderr, "lever-hil serve: cannot watch the CAN bus: {}\n", watch_result.error().message);
    return kRuntimeFailure;
  }
  auto& watch = watch_result.value();

  fmt::print(
      stderr,
      "lever-hil serve: levers powered up at {:+.3f} rad (HSI) and {:+.3f} rad (TOP); waiting for both to be "
      "armed on {}{}\n",
      hsi_angle, top_angle, hsi_config.board.can_interface,
      hsi_config.board.can_interface == top_config.board.can_interface ? "" : " and " + top_config.board.can_interface);

  SimResult result;
  ServeExtras extras;
  RunMetrics metrics(sim.jnd, sim.jnd_absolute_n);
  const auto wall_start = Clock::now();
  auto grid_start = wall_start;
  std::int64_t grid_tick = 0;  // ticks since grid_start
  fw::Tick tick = 0;
  std::optional<fw::Tick> scenario_start;
  const auto scenario_ticks = static_cast<fw::Tick>(std::llround(o.duration_s * 1000.0));
  const auto arm_timeout = std::chrono::duration<double>(o.arm_timeout_s);
  double measured_force = 0.0;

  while (!stop.load(std::memory_order_relaxed)) {
    // Pace to the wall clock: catch up a short lag step by step, slip a long one.
    ++tick;
    ++grid_tick;
    const auto due = grid_start + std::chrono::milliseconds(grid_tick);
    const auto now = Clock::now();
    if (now < due) {
      std::this_thread::sleep_until(due);
    } else {
      const auto lag = std::chrono::duration_cast<std::chrono::milliseconds>(now - due).count();
      extras.max_lag_ms = std::max<std::int64_t>(extras.max_lag_ms, lag);
      if (lag > kMaxCatchUpMs) {
        ++extras.slips;
        grid_start = now;
        grid_tick = 0;
      }
    }
    const std::int64_t now_ms = static_cast<std::int64_t>(tick);
    watch.poll(now_ms);
    const auto& hsi_watch = watch.hsi();
    const auto& top_watch = watch.top();
    const bool hsi_heard = watch.heard_within(hsi_watch, now_ms, kHeardWindowMs);
    const bool top_heard = watch.heard_within(top_watch, now_ms, kHeardWindowMs);
    const bool both_armed = hsi_heard && top_heard && hsi_watch.armed() && top_watch.armed();

    if (!scenario_start) {
      if (both_armed) {
        scenario_start = tick;
        result.homed_at_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
        if (!o.hands_off) world.start_operator(tick);
        fmt::print(stderr, "lever-hil serve: both levers armed after {:.1f} s; {}\n", result.homed_at_s,
                   o.hands_off ? "hands off" : "the operator takes the handle");
      } else if (Clock::now() - wall_start > arm_timeout) {
        fmt::print(stderr, "lever-hil serve: the levers were not armed within {} s (HSI {}, TOP {})\n", o.arm_timeout_s,
                   state_name(hsi_watch), state_name(top_watch));
        return kRuntimeFailure;
      }
    }
    const bool hsi_homing = hsi_heard && hsi_watch.heartbeat->state == protocol::LeverState::homing;
    world.set_hand_on(!hsi_homing, tick);

    const auto hsi_motor = hsi->motor->read();
    const auto top_motor = top->motor->read();
    const fw::MotorCommand hsi_command{hsi_motor.torque_nm, hsi_motor.enabled};
    const fw::MotorCommand top_command{top_motor.torque_nm, top_motor.enabled};
    world.advance(hsi_command, top_command);
    hsi->encoder->set_count(hsi->count_at(world.hsi().angle()));
    top->encoder->set_count(top->count_at(world.top().angle()));

    const double contact = world.contact_force();
    const double hand = world.hand_force();
    // The gauges' amplifier (noise, filter, output rate, display step), then the register layout the lever's
    // config names.
    top_gauge.update(contact, tick);
    if (const auto r = top_gauge.latest()) measured_force = r->raw * sim.gauge.step_n;
    if (top->gauge) top->gauge->set_force(measured_force);
    if (hsi->gauge) {
      hsi_gauge.update(hand, tick);
      if (const auto r = hsi_gauge.latest()) hsi->gauge->set_force(r->raw * sim.gauge.step_n);
    }
    world.update_operator(tick, hand);

    // Frames sent before the scenario (homing, arming) are not the scenario's: taken every tick, counted in it.
    const auto motion_sent = watch.take_motion_frames();
    const auto force_sent = watch.take_force_frames();
    if (!scenario_start) continue;
    const fw::Tick t_ticks = tick - *scenario_start;
    const double t = static_cast<double>(t_ticks) * 1e-3;
    if (!hsi_heard) ++extras.hsi_silent_ms;
    if (!top_heard) ++extras.top_silent_ms;
    const double displayed = watch.force_at_hsi().value_or(0.0);
    if (both_armed) {
      const double dp = world.top().angle() - world.hsi().angle();
      metrics.add_armed_tick(motion_sent, force_sent, dp, displayed, measured_force, contact);
      extras.max_position_error_rad = std::max(extras.max_position_error_rad, std::fabs(dp));
      extras.max_displayed_force_n = std::max(extras.max_displayed_force_n, displayed);
      if (contact > 0.0) extras.hsi_torque_in_contact_sum += hsi_command.enable ? hsi_command.torque_nm : 0.0;
    }
    if (trace) {
      const TraceRow row{t,
                         world.hsi().angle(),
                         world.top().angle(),
                         world.hsi().speed(),
                         watch.position_sent().value_or(0.0),
                         contact,
                         measured_force,
                         displayed,
                         hsi_command.enable ? hsi_command.torque_nm : 0.0,
                         top_command.enable ? top_command.torque_nm : 0.0,
                         hand,
                         static_cast<int>(motion_sent),
                         static_cast<int>(force_sent),
                         state_number(hsi_watch),
                         state_number(top_watch)};
      trace->write(trace_csv_row(row));
    }
    if (t_ticks % 1000 == 0) {
      fmt::print(stderr,
                 "t={:6.1f} s  HSI {}{} {:+.3f} rad {:+.3f} N m | TOP {}{} {:+.3f} rad {:+.3f} N m  contact {:5.2f} N "
                 "shown {:5.2f} N  frames motion {} force {}  lag {} ms\n",
                 t, state_name(hsi_watch), faults_text(hsi_watch), world.hsi().angle(), hsi_command.torque_nm,
                 state_name(top_watch), faults_text(top_watch), world.top().angle(), top_command.torque_nm, contact,
                 displayed, metrics.motion_frames(), metrics.force_frames(), extras.max_lag_ms);
    }
    if (scenario_ticks > 0 && t_ticks >= scenario_ticks) break;
  }

  if (trace) trace->commit();
  metrics.finish(result);
  result.wall_time_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  const double scenario_s = scenario_start ? static_cast<double>(tick - *scenario_start) * 1e-3 : 0.0;
  result.realtime_factor = result.wall_time_s > 0 ? (result.homed_at_s + scenario_s) / result.wall_time_s : 0.0;
  sim.duration_s = scenario_s;

  auto report = report_json(sim, result);
  const auto hsi_encoder = hsi->encoder->stats();
  const auto top_encoder = top->encoder->stats();
  report["serve"] = {
      {"max_position_error_rad", extras.max_position_error_rad},
      {"mean_hsi_torque_in_contact_nm",
       metrics.contact_ticks() > 0 ? extras.hsi_torque_in_contact_sum / static_cast<double>(metrics.contact_ticks())
                                   : 0.0},
      {"max_displayed_force_n", extras.max_displayed_force_n},
      {"slips", extras.slips},
      {"max_lag_ms", extras.max_lag_ms},
      {"silent_ms", {{"hsi", extras.hsi_silent_ms}, {"top", extras.top_silent_ms}}},
      {"encoder_edges", {{"hsi", hsi_encoder.edges}, {"top", top_encoder.edges}}},
      {"encoder_max_backlog", {{"hsi", hsi_encoder.max_backlog}, {"top", top_encoder.max_backlog}}},
      {"gauge_requests", top->gauge ? top->gauge->counters().requests : 0},
      {"can_frames_seen", watch.frames_read()},
  };
  std::FILE* out = trace && trace->is_stdout() ? stderr : stdout;  // the trace has stdout
  if (o.json) {
    fmt::print(out, "{}\n", report.dump());
  } else {
    fmt::print(out, "served {:.1f} s of {} after {:.1f} s of homing and arming\n", scenario_s,
               scenario_name(o.scenario), result.homed_at_s);
    fmt::print(out, "  packets: velocity {:.1f} %, force {:.1f} % of 1 kHz (while both armed: {:.1f} s)\n",
               100 * result.velocity_packet_rate, 100 * result.force_packet_rate,
               1e-3 * static_cast<double>(result.armed_ticks));
    fmt::print(out,
               "  position rmse {:.2f} mrad (max {:.2f}), force rmse {:.3f} N, force off by more than a JND {:.1f} %\n",
               1000 * result.position_rmse_rad, 1000 * extras.max_position_error_rad, result.force_rmse_n,
               100 * result.force_jnd_violation);
    fmt::print(out,
               "  in contact {:.0f} % of the time at {:.2f} N on average; the world slipped {} times (max lag {} ms)\n",
               100 * result.contact_share, result.mean_contact_force_n, extras.slips, extras.max_lag_ms);
  }
  return 0;
}

}  // namespace lever::hil
