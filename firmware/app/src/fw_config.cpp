#include "lever/app/fw_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <string>

#include "lever/program/choices.hpp"
#include "lever/program/text.hpp"

namespace lever::app {
namespace {

// Polls in a row that may fail without the force going stale (docs/modbus-gauge.md, "Timing").
constexpr int kMissedPollsTolerated = 1;

using codec::Mode;
using fw::Tick;

const program::ConfigSchema::Choices<Mode> kModes = [] {
  program::ConfigSchema::Choices<Mode> modes;
  for (const Mode m : codec::kAllModes) modes.emplace_back(codec::name(m), m);
  return modes;
}();

void bind_codec(program::ConfigSchema& s, const std::string& section, codec::Config<double>& c,
                const std::string& unit) {
  s.choice(section + ".mode", c.mode, kModes, "reference: last value sent (deadband) or the linear predictor");
  s.number(section + ".p", c.p, 0.0, 6.5535, "", "Weber fraction: a sample is sent when it differs by more than p");
  s.number(section + ".floor", c.floor, 0.0, 65.535, unit, "absolute deadband floor (0: the paper's rule)");
  s.number(section + ".filter_hz", c.filter_hz, 0.0, 500.0, "Hz", "prefilter cut-off, below Nyquist (0: off)");
}

}  // namespace

const board::ModbusGaugeConfig& default_gauge() {
  static const board::ModbusGaugeConfig gauge = board::preset_gross_weight_int32(board::ModbusTcpEndpoint{});
  return gauge;
}

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

board::GpioEncoderConfig encoder_config(const BoardConfig& b) {
  board::GpioEncoderConfig c;
  c.chip = b.encoder_chip;
  c.line_a = board::LineRef::parse(b.encoder_line_a);
  c.line_b = board::LineRef::parse(b.encoder_line_b);
  if (!b.encoder_line_z.empty()) c.line_z = board::LineRef::parse(b.encoder_line_z);
  c.active_low = b.encoder_active_low;
  c.edge_latency_us = static_cast<std::uint32_t>(b.encoder_edge_latency_us);
  return c;
}

board::ModbusGaugeConfig gauge_config(const BoardConfig& b) {
  board::ModbusGaugeConfig c;
  if (b.gauge_transport == "rtu") {
    c.transport = board::ModbusRtuEndpoint{b.gauge_device,
                                           static_cast<int>(b.gauge_baud),
                                           b.gauge_parity,
                                           8,
                                           static_cast<int>(b.gauge_stop_bits),
                                           static_cast<int>(b.gauge_slave_id)};
  } else {
    c.transport =
        board::ModbusTcpEndpoint{b.gauge_host, static_cast<int>(b.gauge_port), static_cast<int>(b.gauge_unit_id)};
  }
  c.registers = b.gauge_registers;
  c.registers.saturation_raw_min = b.gauge_saturation_raw_min;
  c.registers.saturation_raw_max = b.gauge_saturation_raw_max;
  c.poll_period = std::chrono::microseconds(b.gauge_poll_us);
  c.response_timeout = std::chrono::microseconds(b.gauge_timeout_us);
  c.reconnect_backoff_initial = std::chrono::milliseconds(b.gauge_reconnect_backoff_ms);
  if (c.reconnect_backoff_max < c.reconnect_backoff_initial) c.reconnect_backoff_max = c.reconnect_backoff_initial;
  return c;
}

board::PwmMotorConfig motor_config(const BoardConfig& b) {
  board::PwmMotorConfig c;
  c.sysfs_root = b.motor_sysfs_root;
  c.pwm_chip = static_cast<unsigned>(b.motor_pwm_chip);
  c.pwm_channel = static_cast<unsigned>(b.motor_pwm_channel);
  c.period_ns = static_cast<std::uint32_t>(b.motor_period_ns);
  c.pwm_inversed = b.motor_pwm_inversed;
  c.torque_constant_nm_per_a = b.motor_torque_constant_nm_per_a;
  c.gear_ratio = b.motor_gear_ratio;
  c.full_scale_current_a = b.motor_full_scale_current_a;
  c.max_duty = b.motor_max_duty;
  c.deadband_nm = b.motor_deadband_nm;
  auto line = [&](const std::string& name) -> std::optional<board::MotorLineConfig> {
    if (name.empty()) return std::nullopt;
    return board::MotorLineConfig{b.motor_line_chip, board::LineRef::parse(name), b.motor_lines_active_low};
  };
  c.enable_line = line(b.motor_enable_line);
  c.direction_line = line(b.motor_direction_line);
  c.fault_line = line(b.motor_fault_line);
  c.positive_torque_only = !c.direction_line;
  return c;
}

board::RealtimeConfig realtime_config(const BoardConfig& b) {
  board::RealtimeConfig c;
  c.fifo_priority = static_cast<int>(b.realtime_priority);
  if (!b.realtime_cpus.empty()) c.cpus = board::parse_cpu_list(b.realtime_cpus).value_or(std::vector<unsigned>{});
  c.lock_memory = b.realtime_lock_memory;
  c.prefault_stack_bytes = static_cast<std::size_t>(b.realtime_prefault_stack_kib) * 1024;
  return c;
}

board::LoopWatchdogConfig watchdog_config(const BoardConfig& b) {
  return {b.watchdog_device, std::chrono::seconds(b.watchdog_timeout_s)};
}

board::BoardCanPortConfig can_config(const FwConfig& config) {
  board::BoardCanPortConfig c;
  c.interface = config.board.can_interface;
  c.pair = config.lever.pair;
  c.link_retry_ms = static_cast<std::uint32_t>(config.board.can_link_retry_ms);
  c.link_retry_max_ms = static_cast<std::uint32_t>(config.board.can_link_retry_max_ms);
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
  auto& l = config.lever;
  s.choice("lever.role", l.role, {{"hsi", protocol::Role::hsi}, {"top", protocol::Role::top}},
           "HSI: the operator's lever; TOP: the lever at the wall");
  s.integer("lever.pair", l.pair, 0, protocol::kPairCount - 1, "", "lever pair, selects the CAN ids");

  s.integer("link.heartbeat_ms", l.heartbeat_period, 1, 1000, "ms", "heartbeat period");
  s.integer("link.comms_timeout_ms", l.comms_timeout, 1, 60000, "ms", "peer silent this long latches COMMS");
  s.integer("link.refresh_ms", l.refresh_period, 1, 30000, "ms", "a data frame at least this often");
  s.integer("link.rest_repeat_ms", l.rest_repeat, 0, 30000, "ms",
            "a frame that brings a stream to rest is sent again this much later (0: never)");

  bind_codec(s, "codec.motion", l.motion_codec, "rad/s");
  s.choice("codec.motion.velocity", l.motion_velocity,
           {{fw::name(fw::MotionVelocity::difference), fw::MotionVelocity::difference},
            {fw::name(fw::MotionVelocity::estimate), fw::MotionVelocity::estimate}},
           "HSI sends the quantized position's backward difference (the paper's; 0 at rest) or the velocity estimate");
  bind_codec(s, "codec.force", l.force_codec, "N");

  s.number("encoder.counts_per_rev", l.counts_per_rev, 1.0, 1e8, "counts", "counts per turn (lines x4)");
  s.integer("encoder.counter_bits", l.counter_bits, 8, 32, "bits", "width of a hardware counter");
  s.integer("encoder.illegal_threshold", l.decoder.illegal_threshold, 0, 1000000, "",
            "illegal transitions tolerated before ENCODER latches");
  s.choice("velocity.method", l.velocity.method,
           {{"tracking_loop", fw::VelocityMethod::tracking_loop},
            {"backward_difference", fw::VelocityMethod::backward_difference}},
           "velocity estimate");
  s.number("velocity.bandwidth_rad_s", l.velocity.bandwidth_rad_s, 1.0, 2000.0, "rad/s", "tracking loop bandwidth");

  s.number("gauge.newton_per_unit", l.gauge.newton_per_count, 1e-12, 1e6, "N",
           "newtons per amplifier unit (ADC count, or 1 when the amplifier reports newtons)");
  s.number("gauge.offset", l.gauge.offset_counts, -1e12, 1e12, "units", "zero-force reading, replaced by a tare");
  s.number("gauge.raw_min", l.gauge.raw_min, -1e12, 1e12, "units", "readings at or below are saturated");
  s.number("gauge.raw_max", l.gauge.raw_max, -1e12, 1e12, "units", "readings at or above are saturated");
  s.integer("gauge.stale_ms", l.gauge.stale_after, 1, 10000, "ms", "an older reading gives no force at all");
  s.integer("gauge.tare_samples", l.gauge.tare_samples, 1, 10000, "", "fresh readings averaged by a tare");
  s.boolean("gauge.used", l.use_force_sensor, "the lever reads its gauge (TOP: always; HSI: closed-loop display)");

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

  s.number("timing.overrun_periods", l.timing.overrun_periods, 1.0, 100.0, "periods",
           "a longer step interval is an overrun (counted)");
  s.integer("timing.fault_after_ms", l.timing.fault_after, 1, 1000, "ms",
            "a longer step interval latches TIMING; so does more than fault_after_ms - 1 lost in a window");
  s.integer("timing.window_ms", l.timing.window, 1, fw::StepTiming::kMaxWindow, "ms",
            "lost time (late intervals less a period, long steps) is summed over any window this long");
  s.integer("timing.long_step_us", l.timing.long_step_us, 1, 1000000, "us",
            "a step longer than this counts its whole duration as lost time");

  s.number("control.position.kp_nm_per_rad", l.position.kp, 0.0, 1000.0, "N m/rad", "TOP position gain");
  s.number("control.position.kd_nms", l.position.kd, 0.0, 100.0, "N m s/rad", "TOP velocity gain");
  s.number("control.position.kff_nms", l.position.kff_velocity, 0.0, 100.0, "N m s/rad", "velocity feed-forward");
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

  s.number("safety.torque_limit_nm", l.torque_limit_nm, 1e-3, 100.0, "N m", "never exceeded");
  s.integer("safety.torque_saturation_ms", l.torque_saturation_ticks, 1, 60000, "ms",
            "demand above the limit this long latches TORQUE_LIMIT");
  s.number("safety.position_min_rad", l.position_min_rad, -100.0, 100.0, "rad", "allowed range, checked when homed");
  s.number("safety.position_max_rad", l.position_max_rad, -100.0, 100.0, "rad", "allowed range, checked when homed");
  s.number("safety.safe_hold_torque_nm", l.safe_hold_torque_nm, 0.0, 100.0, "N m", "TOP hold after a fault...");
  s.integer("safety.safe_hold_ms", l.safe_hold_ticks, 0, 60000, "ms", "...for this long, then zero torque");

  auto& b = config.board;
  s.text("board.can.interface", b.can_interface, "SocketCAN interface");
  s.integer("board.can.link_retry_ms", b.can_link_retry_ms, 1, 60000, "ms",
            "a link that is down is checked again after...");
  s.integer("board.can.link_retry_max_ms", b.can_link_retry_max_ms, 1, 600000, "ms", "...doubling up to this");
  s.text("board.encoder.chip", b.encoder_chip, "GPIO chip: path, name or label");
  s.text("board.encoder.line_a", b.encoder_line_a, "line A by name or offset");
  s.text("board.encoder.line_b", b.encoder_line_b, "line B by name or offset");
  s.text("board.encoder.line_z", b.encoder_line_z, "index line by name or offset; empty: none");
  s.boolean("board.encoder.active_low", b.encoder_active_low, "all encoder lines inverted");
  s.integer("board.encoder.edge_latency_us", b.encoder_edge_latency_us, 0, 100000, "us",
            "how long an edge may take to show in the kernel's event queue");

  s.choice("board.gauge.transport", b.gauge_transport, {{"tcp", std::string("tcp")}, {"rtu", std::string("rtu")}},
           "the amplifier's Modbus link");
  s.text("board.gauge.host", b.gauge_host, "tcp: the amplifier's numeric IPv4 or IPv6 address");
  s.integer("board.gauge.port", b.gauge_port, 1, 65535, "", "tcp: port");
  s.integer("board.gauge.unit_id", b.gauge_unit_id, 0, 255, "", "tcp: unit id (255: the device itself)");
  s.text("board.gauge.device", b.gauge_device, "rtu: serial device");
  s.integer("board.gauge.baud", b.gauge_baud, 1200, 921600, "baud", "rtu: a standard rate");
  s.choice("board.gauge.parity", b.gauge_parity,
           {{"none", board::Parity::none}, {"even", board::Parity::even}, {"odd", board::Parity::odd}}, "rtu: parity");
  s.integer("board.gauge.stop_bits", b.gauge_stop_bits, 1, 2, "", "rtu: stop bits");
  s.integer("board.gauge.slave_id", b.gauge_slave_id, 1, 247, "", "rtu: slave id");
  auto& r = b.gauge_registers;
  s.choice("board.gauge.function", r.function,
           {{"holding", board::RegisterFunction::holding}, {"input", board::RegisterFunction::input}},
           "register table (function code 3 or 4)");
  s.integer("board.gauge.address", r.address, 0, 65535, "", "first register, 0-based (a manual's 40001 is 0)");
  s.choice("board.gauge.type", r.type,
           {{"int16", board::RegisterType::int16},
            {"uint16", board::RegisterType::uint16},
            {"int32", board::RegisterType::int32},
            {"uint32", board::RegisterType::uint32},
            {"float32", board::RegisterType::float32}},
           "register type");
  s.choice("board.gauge.word_order", r.word_order,
           {{"high_first", board::WordOrder::high_first}, {"low_first", board::WordOrder::low_first}},
           "32-bit types: which word the lower address holds");
  s.number("board.gauge.scale", r.scale, -1e12, 1e12, "N", "newtons per raw unit (not 0)");
  s.number("board.gauge.offset", r.offset, -1e12, 1e12, "N", "added after scaling");
  s.number("board.gauge.saturation_raw_min", b.gauge_saturation_raw_min, -1e15, 1e15, "raw",
           "a raw value at or below is the amplifier's range end");
  s.number("board.gauge.saturation_raw_max", b.gauge_saturation_raw_max, -1e15, 1e15, "raw",
           "a raw value at or above is the amplifier's range end");
  s.integer("board.gauge.poll_us", b.gauge_poll_us, 100, 10000000, "us", "poll period (RTU at 115200 baud: 5-10 ms)");
  s.integer("board.gauge.timeout_us", b.gauge_timeout_us, 1000, 1000000, "us",
            "response timeout (a TCP connect's too); gauge.stale_ms must outlast one missed poll");
  s.integer("board.gauge.reconnect_backoff_ms", b.gauge_reconnect_backoff_ms, 1, 60000, "ms",
            "wait before a reconnect, doubled while it fails (TCP's first is at once; RTU's lets a late answer land)");

  s.text("board.motor.sysfs_root", b.motor_sysfs_root, "where sysfs is (tests: a tree of their own)");
  s.integer("board.motor.pwm_chip", b.motor_pwm_chip, 0, 1023, "", "class/pwm/pwmchipN");
  s.integer("board.motor.pwm_channel", b.motor_pwm_channel, 0, 1023, "", "the chip's channel");
  s.integer("board.motor.period_ns", b.motor_period_ns, 1000, 100000000, "ns", "PWM period (50000: 20 kHz)");
  s.boolean("board.motor.pwm_inversed", b.motor_pwm_inversed, "the board inverts the PWM on its way to the driver");
  s.number("board.motor.torque_constant_nm_per_a", b.motor_torque_constant_nm_per_a, 1e-6, 100.0, "N m/A",
           "the motor's Kt");
  s.number("board.motor.gear_ratio", b.motor_gear_ratio, 1e-3, 1000.0, "", "lever torque per motor torque");
  s.number("board.motor.full_scale_current_a", b.motor_full_scale_current_a, 1e-3, 1000.0, "A",
           "the driver's current at 100 % duty");
  s.number("board.motor.max_duty", b.motor_max_duty, 0.0, 1.0, "", "the duty never goes above this");
  s.number("board.motor.deadband_nm", b.motor_deadband_nm, 0.0, 100.0, "N m", "smaller torques give zero duty");
  s.text("board.motor.line_chip", b.motor_line_chip, "GPIO chip of the driver's lines");
  s.text("board.motor.enable_line", b.motor_enable_line, "driver enable (output) by name or offset; empty: none");
  s.text("board.motor.direction_line", b.motor_direction_line,
         "direction (output; asserted: negative torque); empty: positive torque only");
  s.text("board.motor.fault_line", b.motor_fault_line, "driver fault (input); empty: none");
  s.boolean("board.motor.lines_active_low", b.motor_lines_active_low, "the driver's lines are active low");

  s.integer("board.realtime.priority", b.realtime_priority, 0, 99, "", "SCHED_FIFO priority (0: none)");
  s.text("board.realtime.cpus", b.realtime_cpus,
         "the loop's CPUs, as taskset takes them (\"2\", \"0,2-3\"); empty: any");
  s.boolean("board.realtime.lock_memory", b.realtime_lock_memory, "mlockall, so no page fault stalls a step");
  s.integer("board.realtime.prefault_stack_kib", b.realtime_prefault_stack_kib, 0, 65536, "KiB",
            "stack touched at start");

  s.text("board.watchdog.device", b.watchdog_device,
         "a hardware watchdog fed only while the loop advances, e.g. /dev/watchdog0; empty: none");
  s.integer("board.watchdog.timeout_s", b.watchdog_timeout_s, 1, 60, "s",
            "the hardware watchdog resets the board after this long unfed");
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
  if (!(l.gauge.raw_min < l.gauge.raw_max))
    return fail("gauge.raw_min, gauge.raw_max", "the minimum must be below the maximum");
  if (const auto gap = board::longest_gap(gauge_config(out.config.board), kMissedPollsTolerated);
      static_cast<std::int64_t>(l.gauge.stale_after) * 1000 <= gap.count()) {
    return fail(
        "gauge.stale_ms",
        fmt::format("{} ms does not outlast one missed poll: with these board.gauge timings a reading may be "
                    "{:.1f} ms old (poll_us + 2 x timeout_us + {}); at least {} ms",
                    l.gauge.stale_after, static_cast<double>(gap.count()) / 1000.0,
                    out.config.board.gauge_transport == "rtu" ? "reconnect_backoff_ms" : "timeout_us for the reconnect",
                    gap.count() / 1000 + 1));
  }
  const auto problems = encoder_config(out.config.board).validate();
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
    if (!b.motor_enable_line.empty() || !b.motor_direction_line.empty() || !b.motor_fault_line.empty())
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
