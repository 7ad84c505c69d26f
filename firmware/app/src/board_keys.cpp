#include "lever/app/board_keys.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>

#include "lever/program/choices.hpp"

namespace lever::app {
namespace {

using program::ConfigSchema;

// A line by name or by offset on its chip ("ENC_A", "17"), printed back as it was written.
void line(ConfigSchema& s, std::string key, board::LineRef& value, std::string doc) {
  s.text_as<board::LineRef>(
      std::move(key), value, [](const std::string& text) { return board::LineRef::parse(text); },
      [](const board::LineRef& l) { return l.text(); }, std::move(doc));
}

// The same, or none for "".
void optional_line(ConfigSchema& s, std::string key, std::optional<board::LineRef>& value, std::string doc) {
  s.text_as<std::optional<board::LineRef>>(
      std::move(key), value,
      [](const std::string& text) -> std::optional<board::LineRef> {
        if (text.empty()) return std::nullopt;
        return board::LineRef::parse(text);
      },
      [](const std::optional<board::LineRef>& l) { return l ? l->text() : std::string(); }, std::move(doc));
}

void bind_gauge_link(ConfigSchema& s, GaugeLink& link) {
  using Transport = GaugeLink::Transport;
  s.choice("board.gauge.transport", link.transport, {{"tcp", Transport::tcp}, {"rtu", Transport::rtu}},
           "the amplifier's Modbus link");
  s.text("board.gauge.host", link.tcp.host, "tcp: the amplifier's numeric IPv4 or IPv6 address");
  s.integer("board.gauge.port", link.tcp.port, 1, 65535, "", "tcp: port");
  s.integer("board.gauge.unit_id", link.tcp.unit_id, 0, 255, "", "tcp: unit id (255: the device itself)");
  s.text("board.gauge.device", link.rtu.device, "rtu: serial device");
  s.integer("board.gauge.baud", link.rtu.baud, 1200, 921600, "baud", "rtu: a standard rate");
  s.choice("board.gauge.parity", link.rtu.parity, program::choices_of(board::kAllParities), "rtu: parity");
  s.integer("board.gauge.stop_bits", link.rtu.stop_bits, 1, 2, "", "rtu: stop bits");
  s.integer("board.gauge.slave_id", link.rtu.slave_id, 1, 247, "", "rtu: slave id");
}

void bind_gauge_registers(ConfigSchema& s, board::GaugeRegisterMap& r) {
  s.choice("board.gauge.function", r.function, program::choices_of(board::kAllRegisterFunctions),
           "register table (function code 3 or 4)");
  s.integer("board.gauge.address", r.address, 0, 65535, "", "first register, 0-based (a manual's 40001 is 0)");
  s.choice("board.gauge.type", r.type, program::choices_of(board::kAllRegisterTypes), "register type");
  s.choice("board.gauge.word_order", r.word_order, program::choices_of(board::kAllWordOrders),
           "32-bit types: which word the lower address holds");
  s.number("board.gauge.scale", r.scale, -1e12, 1e12, "N", "newtons per raw unit (not 0)");
  s.number("board.gauge.offset", r.offset, -1e12, 1e12, "N", "added after scaling");
  s.number("board.gauge.saturation_raw_min", r.saturation_raw_min, -1e15, 1e15, "raw",
           "a raw value at or below is the amplifier's range end");
  s.number("board.gauge.saturation_raw_max", r.saturation_raw_max, -1e15, 1e15, "raw",
           "a raw value at or above is the amplifier's range end");
}

void bind_motor_lines(ConfigSchema& s, MotorLines& lines) {
  s.text("board.motor.line_chip", lines.chip, "GPIO chip of the driver's lines");
  optional_line(s, "board.motor.enable_line", lines.enable, "driver enable (output) by name or offset; empty: none");
  optional_line(s, "board.motor.direction_line", lines.direction,
                "direction (output; asserted: negative torque); empty: positive torque only");
  optional_line(s, "board.motor.fault_line", lines.fault, "driver fault (input); empty: none");
  s.boolean("board.motor.lines_active_low", lines.active_low, "the driver's lines are active low");
}

}  // namespace

void bind_can(ConfigSchema& s, board::BoardCanPortConfig& can) {
  s.text("board.can.interface", can.interface, "SocketCAN interface");
  s.integer("board.can.link_retry_ms", can.link_retry_ms, 1, 60000, "ms",
            "a link that is down is checked again after...");
  s.integer("board.can.link_retry_max_ms", can.link_retry_max_ms, 1, 600000, "ms", "...doubling up to this");
}

void bind_encoder(ConfigSchema& s, board::GpioEncoderConfig& encoder) {
  s.text("board.encoder.chip", encoder.chip, "GPIO chip: path, name or label");
  line(s, "board.encoder.line_a", encoder.line_a, "line A by name or offset");
  line(s, "board.encoder.line_b", encoder.line_b, "line B by name or offset");
  optional_line(s, "board.encoder.line_z", encoder.line_z, "index line by name or offset; empty: none");
  s.boolean("board.encoder.active_low", encoder.active_low, "all encoder lines inverted");
  s.integer("board.encoder.edge_latency_us", encoder.edge_latency_us, 0, 100000, "us",
            "how long an edge may take to show in the kernel's event queue");
}

void bind_gauge(ConfigSchema& s, board::ModbusGaugeConfig& gauge, GaugeLink& link) {
  bind_gauge_link(s, link);
  bind_gauge_registers(s, gauge.registers);
  s.duration("board.gauge.poll_us", gauge.poll_period, 100, 10000000, "us",
             "poll period (RTU at 115200 baud: 5-10 ms)");
  s.duration("board.gauge.timeout_us", gauge.response_timeout, 1000, 1000000, "us",
             "response timeout (a TCP connect's too); gauge.stale_ms must outlast one missed poll");
  s.duration("board.gauge.reconnect_backoff_ms", gauge.reconnect_backoff_initial, 1, 60000, "ms",
             "wait before a reconnect, doubled while it fails (TCP's first is at once; RTU's lets a late answer land)");
}

void bind_motor(ConfigSchema& s, board::PwmMotorConfig& motor, MotorLines& lines) {
  s.text("board.motor.sysfs_root", motor.sysfs_root, "where sysfs is (tests: a tree of their own)");
  s.integer("board.motor.pwm_chip", motor.pwm_chip, 0, 1023, "", "class/pwm/pwmchipN");
  s.integer("board.motor.pwm_channel", motor.pwm_channel, 0, 1023, "", "the chip's channel");
  s.integer("board.motor.period_ns", motor.period_ns, 1000, 100000000, "ns", "PWM period (50000: 20 kHz)");
  s.boolean("board.motor.pwm_inversed", motor.pwm_inversed, "the board inverts the PWM on its way to the driver");
  s.number("board.motor.torque_constant_nm_per_a", motor.torque_constant_nm_per_a, 1e-6, 100.0, "N m/A",
           "the motor's Kt");
  s.number("board.motor.gear_ratio", motor.gear_ratio, 1e-3, 1000.0, "", "lever torque per motor torque");
  s.number("board.motor.full_scale_current_a", motor.full_scale_current_a, 1e-3, 1000.0, "A",
           "the driver's current at 100 % duty");
  s.number("board.motor.max_duty", motor.max_duty, 0.0, 1.0, "", "the duty never goes above this");
  s.number("board.motor.deadband_nm", motor.deadband_nm, 0.0, 100.0, "N m", "smaller torques give zero duty");
  bind_motor_lines(s, lines);
}

void bind_realtime(ConfigSchema& s, board::RealtimeConfig& realtime, std::string& cpus) {
  s.integer("board.realtime.priority", realtime.fifo_priority, 0, 99, "", "SCHED_FIFO priority (0: none)");
  s.text("board.realtime.cpus", cpus, "the loop's CPUs, as taskset takes them (\"2\", \"0,2-3\"); empty: any");
  s.boolean("board.realtime.lock_memory", realtime.lock_memory, "mlockall, so no page fault stalls a step");
  s.custom(
      "board.realtime.prefault_stack_kib", "KiB", "stack touched at start",
      [&realtime](const toml::node& n) -> std::optional<std::string> {
        std::int64_t kib = 0;
        if (auto e = ConfigSchema::read_integer(n, 0, 65536, kib)) return e;
        realtime.prefault_stack_bytes = static_cast<std::size_t>(kib) * 1024;
        return std::nullopt;
      },
      [&realtime] { return std::to_string(realtime.prefault_stack_bytes / 1024); });
}

void bind_watchdog(ConfigSchema& s, board::LoopWatchdogConfig& watchdog) {
  s.text("board.watchdog.device", watchdog.device,
         "a hardware watchdog fed only while the loop advances, e.g. /dev/watchdog0; empty: none");
  s.duration("board.watchdog.timeout_s", watchdog.device_timeout, 1, 60, "s",
             "the hardware watchdog resets the board after this long unfed");
}

void bind_board(ConfigSchema& s, BoardConfig& board) {
  bind_can(s, board.can);
  bind_encoder(s, board.encoder);
  bind_gauge(s, board.gauge, board.gauge_link);
  bind_motor(s, board.motor, board.motor_lines);
  bind_realtime(s, board.realtime, board.realtime_cpus);
  bind_watchdog(s, board.watchdog);
}

}  // namespace lever::app
