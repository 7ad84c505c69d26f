#include "lever/app/fw_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "lever/app/board_keys.hpp"
#include "lever/board/modbus_gauge_presets.hpp"
#include "lever/codec_cli/codec_options.hpp"
#include "lever/program/choices.hpp"
#include "lever/program/text.hpp"

namespace lever::app {
namespace {

// Polls in a row that may fail without the force going stale (docs/modbus-gauge.md, "Timing").
constexpr int kMissedPollsTolerated = 1;

using fw::Tick;

void bind_lever(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.choice("lever.role", l.role, {{"hsi", protocol::Role::hsi}, {"top", protocol::Role::top}},
           "HSI: the operator's lever; TOP: the lever at the wall");
  s.integer("lever.pair", l.pair, 0, protocol::kPairCount - 1, "", "lever pair, selects the CAN ids");
}

void bind_link(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.integer("link.heartbeat_ms", l.heartbeat_period, 1, 1000, "ms", "heartbeat period");
  s.integer("link.comms_timeout_ms", l.comms_timeout, 1, 60000, "ms", "peer silent this long latches COMMS");
  s.integer("link.refresh_ms", l.refresh_period, 1, 30000, "ms", "a data frame at least this often");
  s.integer("link.rest_repeat_ms", l.rest_repeat, 0, 30000, "ms",
            "a frame that brings a stream to rest is sent again this much later (0: never)");
}

// The values a lever applies and confirms over CAN, in the ranges lever-ctl set-deadband sends: a file gives a lever
// no value a command could not.
void bind_codecs(program::ConfigSchema& s, fw::LeverConfig& l) {
  codec_cli::bind_keys(s, "codec.motion", l.motion_codec, codec_cli::kVelocity, codec_cli::kOnWire);
  s.choice("codec.motion.velocity", l.motion_velocity,
           {{fw::name(fw::MotionVelocity::difference), fw::MotionVelocity::difference},
            {fw::name(fw::MotionVelocity::estimate), fw::MotionVelocity::estimate}},
           "HSI sends the quantized position's backward difference (the paper's; 0 at rest) or the velocity estimate");
  codec_cli::bind_keys(s, "codec.force", l.force_codec, codec_cli::kForce, codec_cli::kOnWire);
}

void bind_encoder_and_velocity(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.number("encoder.counts_per_rev", l.counts_per_rev, 1.0, 1e8, "counts", "counts per turn (lines x4)");
  s.integer("encoder.counter_bits", l.counter_bits, 8, 32, "bits", "width of a hardware counter");
  s.integer("encoder.illegal_threshold", l.decoder.illegal_threshold, 0, 1000000, "",
            "illegal transitions tolerated before ENCODER latches");
  s.choice("velocity.method", l.velocity.method, program::choices_of(fw::kAllVelocityMethods),
           "velocity estimate: the tracking loop's integrator, the rate of its angle estimate (less lag, more noise), "
           "or the backward difference");
  // Whole rad/s below the 1 ms Euler step's stability limit, so the largest value accepted is a stable loop.
  s.number("velocity.bandwidth_rad_s", l.velocity.bandwidth_rad_s, 1.0,
           std::floor(fw::VelocityEstimator::kMaxStableBandwidthRadS), "rad/s",
           "tracking loop bandwidth, below the 1 ms loop's stability limit");
}

void bind_force_gauge(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.number("gauge.newton_per_unit", l.gauge.newton_per_count, 1e-12, 1e6, "N",
           "newtons per amplifier unit (ADC count, or 1 when the amplifier reports newtons)");
  s.number("gauge.offset", l.gauge.offset_counts, -1e12, 1e12, "units", "zero-force reading, replaced by a tare");
  s.number("gauge.raw_min", l.gauge.raw_min, -1e12, 1e12, "units", "readings at or below are saturated");
  s.number("gauge.raw_max", l.gauge.raw_max, -1e12, 1e12, "units", "readings at or above are saturated");
  s.integer("gauge.stale_ms", l.gauge.stale_after, 1, 10000, "ms", "an older reading gives no force at all");
  s.integer("gauge.tare_samples", l.gauge.tare_samples, 1, 10000, "", "fresh readings averaged by a tare");
  s.boolean("gauge.used", l.use_force_sensor, "the lever reads its gauge (TOP: always; HSI: closed-loop display)");
}

void bind_homing(program::ConfigSchema& s, fw::LeverConfig& l) {
  auto& h = l.homing;
  s.choice("homing.method", h.method,
           {{"absolute", fw::HomingMethod::absolute},
            {"hard_stop", fw::HomingMethod::hard_stop},
            {"index", fw::HomingMethod::index}},
           "absolute encoder, or home against the end stop, or at the index line");
  s.number("homing.direction", h.direction, -1.0, 1.0, "", "-1 or +1: where the stop or index is");
  s.number("homing.speed_rad_s", h.speed_rad_s, 1e-3, 10.0, "rad/s", "homing speed");
  s.number("homing.kp_nms", h.kp_nms, 0.0, 10.0, "N m s/rad", "homing velocity loop, proportional");
  s.number("homing.ki_nm", h.ki_nm, 0.0, 100.0, "N m/rad", "homing velocity loop, integral");
  s.number("homing.torque_limit_nm", h.torque_limit_nm, 1e-3, 10.0, "N m", "never more while homing");
  s.number("homing.stall_speed_rad_s", h.stall_speed_rad_s, 1e-4, 10.0, "rad/s",
           "slower than this at the torque limit...");
  s.integer("homing.stall_ms", h.stall_ticks, 1, 10000, "ms", "...this long is the stop");
  s.number("homing.home_position_rad", h.home_position_rad, -100.0, 100.0, "rad", "position of the stop or index");
  s.number("homing.max_travel_rad", h.max_travel_rad, 1e-3, 100.0, "rad", "give up after this much travel");
  s.integer("homing.timeout_ms", h.timeout_ticks, 1, 600000, "ms", "give up after this long");
}

void bind_timing(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.number("timing.overrun_periods", l.timing.overrun_periods, 1.0, 100.0, "periods",
           "a longer step interval is an overrun (counted)");
  s.integer("timing.fault_after_ms", l.timing.fault_after, 1, 1000, "ms",
            "a longer step interval latches TIMING; so does more than fault_after_ms - 1 lost in a window");
  s.integer("timing.window_ms", l.timing.window, 1, fw::StepTiming::kMaxWindow, "ms",
            "lost time (late intervals less a period, long steps) is summed over any window this long");
  s.integer("timing.long_step_us", l.timing.long_step_us, 1, 1000000, "us",
            "a step longer than this counts its whole duration as lost time");
}

void bind_control(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.number("control.position.kp_nm_per_rad", l.position.kp, 0.0, 1000.0, "N m/rad", "TOP position gain");
  s.number("control.position.kd_nms", l.position.kd, 0.0, 100.0, "N m s/rad", "TOP velocity gain");
  s.number("control.position.kff_nms", l.position.kff_velocity, 0.0, 100.0, "N m s/rad", "velocity feed-forward");
  s.number("control.position.reference_velocity_cutoff_hz", l.position.reference_velocity_cutoff_hz, 0.0, 499.0, "Hz",
           "the HSI's velocity reaches the D and the feed-forward through a low-pass at this cut-off (0: none)");
  s.number("control.position.approach_speed_rad_s", l.position.approach_speed_rad_s, 1e-3, 100.0, "rad/s",
           "after arming, the TOP walks to the HSI at most this fast");
  s.number("control.display.lever_arm_m", l.display.lever_arm_m, 1e-3, 10.0, "m", "pivot to handle");
  s.number("control.display.gain", l.display.gain, 0.0, 100.0, "", "force scaling TOP to HSI");
  s.boolean("control.display.closed_loop", l.display.closed_loop, "PI on the HSI's own gauge");
  s.number("control.display.kp", l.display.kp, 0.0, 100.0, "", "closed loop: per unit force error");
  s.number("control.display.ki_per_s", l.display.ki, 0.0, 10000.0, "1/s", "closed loop: integral gain");
  s.number("control.display.integral_limit_n", l.display.integral_limit_n, 0.0, 1000.0, "N", "integral clamp");
  s.number("control.display.contact_damping_nms", l.display.contact_damping_nms, 0.0, 100.0, "N m s/rad",
           "HSI damping while a contact force is displayed");
  s.number("control.display.contact_threshold_n", l.display.contact_threshold_n, 0.0, 100.0, "N",
           "displayed force above which the lever is in contact");
  s.choice("control.passivity.mode", l.passivity.mode, program::choices_of(fw::kAllPassivityModes),
           "time-domain passivity: off, observe (observer and energy frames only) or tdpa (the controller acts)");
  s.number("control.passivity.drift_gain_per_s", l.passivity.drift_gain_per_s, 0.0, 999.0, "1/s",
           "TOP with tdpa: pull toward the HSI's position at this rate, within the energy the channel has");
  s.number("control.passivity.reserve_j", l.passivity.reserve_j, 0.0, 999.0, "J",
           "of the port's own input, what it keeps for its own output (0: the literature's per-port TDPA)");
  s.number("control.passivity.reserve_share", l.passivity.reserve_share, 0.0, 1.0, "",
           "of each joule the port takes in, the share that may go to its reserve; the rest goes to the peer");
  s.number("control.passivity.display_spend_time_s", l.passivity.display_spend_time_s, 0.0, 10.0, "s",
           "HSI with tdpa: spend the port's energy over this time constant (0: all at once)");
}

void bind_safety(program::ConfigSchema& s, fw::LeverConfig& l) {
  s.number("safety.torque_limit_nm", l.torque_limit_nm, 1e-3, 100.0, "N m", "never exceeded");
  s.integer("safety.torque_saturation_ms", l.torque_saturation_ticks, 1, 60000, "ms",
            "demand above the limit this long latches TORQUE_LIMIT");
  s.number("safety.position_min_rad", l.position_min_rad, -100.0, 100.0, "rad", "allowed range, checked when homed");
  s.number("safety.position_max_rad", l.position_max_rad, -100.0, 100.0, "rad", "allowed range, checked when homed");
  s.number("safety.safe_hold_torque_nm", l.safe_hold_torque_nm, 0.0, 100.0, "N m", "TOP hold after a fault...");
  s.integer("safety.safe_hold_ms", l.safe_hold_ticks, 0, 60000, "ms", "...for this long, then zero torque");
}

}  // namespace

fw::LeverConfig board_lever_defaults() {
  fw::LeverConfig c;
  c.gauge.newton_per_count = 1.0;
  c.gauge.raw_min = -board::kTestbedLoadCellCapacityN;
  c.gauge.raw_max = board::kTestbedLoadCellCapacityN;
  // The core's 5 ms suits an amplifier that pushes 600 samples a second; polled over Modbus, a reading may be
  // as old as the longest gap with one missed poll (5 + 3 x 10 ms), and one missed poll must not latch
  // FORCE_STALE.
  const auto gap = board::longest_gap(default_gauge(), kMissedPollsTolerated);
  c.gauge.stale_after = static_cast<fw::Tick>((gap.count() + 999) / 1000 + 1);
  return c;
}

board::BoardCanPortConfig can_config(const FwConfig& config) {
  board::BoardCanPortConfig c = config.board.can;
  c.pair = config.lever.pair;
  return c;
}

namespace {

// Relations between keys that make a fault certain at rest, which no key's own range can refuse.
struct RelationProblem {
  std::string keys, text;
};
std::optional<RelationProblem> certain_fault_at_rest(const fw::LeverConfig& l) {
  // At rest the peer's heartbeats and data refreshes are the frames that feed the comms watchdog; a peer configured
  // alike sends one at least every min(heartbeat, refresh), and a frame spends at least a tick in transit.
  const auto gap = std::min(l.heartbeat_period, l.refresh_period);
  if (l.comms_timeout <= gap)
    return RelationProblem{"link.comms_timeout_ms",
                           fmt::format("{} ms is not longer than the gap between the peer's frames at rest ({} ms: "
                                       "link.heartbeat_ms and link.refresh_ms, a peer configured alike): COMMS would "
                                       "latch at rest",
                                       l.comms_timeout, gap)};
  const auto& h = l.homing;
  if (h.method == fw::HomingMethod::absolute) return std::nullopt;
  // The stop is recognised only after stall_ms at it.
  if (h.timeout_ticks <= h.stall_ticks)
    return RelationProblem{"homing.timeout_ms", fmt::format("{} ms is not longer than homing.stall_ms ({} ms): every "
                                                            "homing would time out before it could see the stop",
                                                            h.timeout_ticks, h.stall_ticks)};
  // Homing ends with the lever at home_position_rad, and the range is checked from then on.
  if (h.home_position_rad < l.position_min_rad || h.home_position_rad > l.position_max_rad)
    return RelationProblem{
        "homing.home_position_rad",
        fmt::format("{} rad is outside safety.position_min_rad..position_max_rad ({} to {} rad): POSITION_LIMIT "
                    "would latch the moment homing ends",
                    h.home_position_rad, l.position_min_rad, l.position_max_rad)};
  return std::nullopt;
}

}  // namespace

program::ConfigSchema schema_for(FwConfig& config) {
  program::ConfigSchema s;
  bind_lever(s, config.lever);
  bind_link(s, config.lever);
  bind_codecs(s, config.lever);
  bind_encoder_and_velocity(s, config.lever);
  bind_force_gauge(s, config.lever);
  bind_homing(s, config.lever);
  bind_timing(s, config.lever);
  bind_control(s, config.lever);
  bind_safety(s, config.lever);
  bind_board(s, config.board);
  return s;
}

LoadedConfig load_fw_config(const std::string& path, const ConfigOverrides& overrides) {
  LoadedConfig out;
  auto schema = schema_for(out.config);
  if (auto e = schema.load_file(path)) {
    out.error = *e;
    return out;
  }
  for (const auto& assignment : overrides.sets) {
    if (auto e = schema.load_assignment(assignment, "--set")) {
      out.error = *e;
      return out;
    }
  }
  if (overrides.role) out.config.lever.role = *overrides.role;
  if (overrides.can) {
    if (auto e = schema.load_value("board.can.interface", toml::value<std::string>(*overrides.can), "--can")) {
      out.error = *e;
      return out;
    }
  }
  // What one key cannot say alone.
  const auto& l = out.config.lever;
  auto fail = [&](std::string_view keys, std::string_view problem) {
    out.error = fmt::format("{}: {}: {}", path, keys, program::printable(problem, 400));
    return out;
  };
  if (!(l.position_min_rad < l.position_max_rad))
    return fail("safety.position_min_rad, safety.position_max_rad", "the minimum must be below the maximum");
  if (l.safe_hold_torque_nm > l.torque_limit_nm)
    return fail("safety.safe_hold_torque_nm", "must not exceed safety.torque_limit_nm");
  if (l.homing.torque_limit_nm > l.torque_limit_nm)
    return fail("homing.torque_limit_nm", "must not exceed safety.torque_limit_nm");
  if (l.homing.direction != 1.0 && l.homing.direction != -1.0) return fail("homing.direction", "must be -1 or 1");
  if (auto problem = certain_fault_at_rest(l)) return fail(problem->keys, problem->text);
  if (fw::reference_low_pass_conflicts(l))
    return fail("control.position.reference_velocity_cutoff_hz, control.passivity.mode",
                "must be 0 on a TOP under tdpa: after the passivity port the low-pass would apply a velocity the port "
                "never counted (docs/firmware.md, \"Passivity under delay\")");
  if (!(l.gauge.raw_min < l.gauge.raw_max))
    return fail("gauge.raw_min, gauge.raw_max", "the minimum must be below the maximum");
  if (const auto gap = board::longest_gap(gauge_config(out.config.board), kMissedPollsTolerated);
      static_cast<std::int64_t>(l.gauge.stale_after) * 1000 <= gap.count()) {
    const bool rtu = out.config.board.gauge_link.transport == GaugeLink::Transport::rtu;
    return fail("gauge.stale_ms",
                fmt::format("{} ms does not outlast one missed poll: with these board.gauge timings a reading may be "
                            "{:.1f} ms old (poll_us + 2 x timeout_us + {}); at least {} ms",
                            l.gauge.stale_after, static_cast<double>(gap.count()) / 1000.0,
                            rtu ? "reconnect_backoff_ms" : "timeout_us for the reconnect", gap.count() / 1000 + 1));
  }
  const auto problems = out.config.board.encoder.validate();
  if (!problems.empty()) return fail("board.encoder", problems.front());
  if (const auto problem = board::validate(gauge_config(out.config.board))) return fail("board.gauge", *problem);
  if (const auto p = motor_config(out.config.board).validate(); !p.empty()) return fail("board.motor", p.front());
  if (!out.config.board.realtime_cpus.empty() && !board::parse_cpu_list(out.config.board.realtime_cpus))
    return fail("board.realtime.cpus", "not a CPU list like \"2\" or \"0,2-3\"");
  if (const auto p = realtime_config(out.config.board).validate(); !p.empty()) return fail("board.realtime", p.front());
  if (const auto p = can_config(out.config).validate(); !p.empty()) {
    if (!overrides.can) return fail("board.can", p.front());
    out.error = fmt::format("--can: board.can.{}", program::printable(p.front(), 400));
    return out;
  }
  if (!fw::is_valid(l)) return fail("(several keys)", "the combination is not valid");
  return out;
}

MotorKeys motor_keys_from(const toml::table& table, const std::string& source, MotorKeysRequired required) {
  constexpr std::string_view kMotor = "board.motor.";
  MotorKeys out;
  FwConfig config;
  auto schema = schema_for(config);
  auto each = schema.load_table_each(table, source);
  // The motor's problems first: they are the ones that decide.
  std::stable_partition(each.begin(), each.end(), [&](const program::ConfigSchema::KeyProblem& p) {
    return p.key.empty() || p.key.starts_with(kMotor);
  });
  bool motor_readable = true;
  for (const auto& p : each) {
    if (p.key.empty() || p.key.starts_with(kMotor)) motor_readable = false;
    out.problems.push_back(p.message);
  }
  // A key left out is its default, and the defaults name a motor too (pwmchip0/pwm0, gpiochip0's MOTOR_EN): on
  // a board that has it, a stop would act on a channel nobody named, maybe another lever's.
  std::vector<std::string> named;
  if (required == MotorKeysRequired::every_key) {
    named = schema.keys(kMotor);
  } else {
    const auto& b = config.board;
    named = {"board.motor.pwm_chip", "board.motor.pwm_channel", "board.motor.enable_line", "board.motor.direction_line",
             "board.motor.fault_line"};
    if (b.motor_lines.enable || b.motor_lines.direction || b.motor_lines.fault)
      named.push_back("board.motor.line_chip");
  }
  std::string missing;
  for (const auto& key : named)
    if (!table.at_path(key)) missing += (missing.empty() ? "" : ", ") + key;
  if (!missing.empty() && motor_readable) {
    out.problems.insert(
        out.problems.begin(),
        fmt::format("{}: {}: missing; the motor is named by its keys, never by their defaults", source, missing));
    motor_readable = false;
  }
  if (motor_readable) {
    const auto motor = motor_config(config.board);
    if (const auto invalid = motor.validate(); !invalid.empty()) {
      for (const auto& p : invalid)
        out.problems.insert(out.problems.begin(), fmt::format("{}: board.motor: {}", source, p));
    } else {
      out.motor = motor;
    }
  }
  return out;
}

MotorKeys load_motor_keys(const std::string& path) {
  const auto parsed = program::ConfigSchema::parse_file(path);
  if (!parsed.error.empty()) return {std::nullopt, {parsed.error}};
  MotorKeys out = motor_keys_from(parsed.table, path, MotorKeysRequired::identity);
  // What one key cannot say alone, said once every key has loaded.
  if (out.motor && out.problems.empty()) {
    if (auto whole = load_fw_config(path); !whole.error.empty()) out.problems.push_back(whole.error);
  }
  return out;
}

std::string motor_keys_toml(FwConfig config) { return schema_for(config).print("board.motor."); }

}  // namespace lever::app
