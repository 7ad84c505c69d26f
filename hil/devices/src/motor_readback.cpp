#include "lever/hil/devices/motor_readback.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <optional>
#include <string_view>

#include "fake_pwm_tree.hpp"
#include "lever/board/config_error.hpp"
#include "lever/board/unique_fd.hpp"
#include "lever/hil/devices/pwm_controller_state.hpp"
#include "sim_line.hpp"

namespace lever::hil::devices {

namespace {

using board::Error;
using board::UniqueFd;

// A regular file rewritten by pwrite at offset 0 keeps the tail of a longer old value ("0\n000\n"): every
// value ends in a newline, so the value is the first line.
std::optional<std::string_view> first_line(int fd, char (&buffer)[32]) noexcept {
  const ssize_t got = ::pread(fd, buffer, sizeof buffer, 0);
  if (got <= 0) return std::nullopt;
  const std::string_view text(buffer, static_cast<std::size_t>(got));
  const auto end = text.find('\n');
  if (end == std::string_view::npos) return std::nullopt;  // nothing written yet, or cut off mid-write
  return text.substr(0, end);
}

std::optional<std::uint64_t> read_unsigned(int fd) noexcept {
  char buffer[32];
  const auto line = first_line(fd, buffer);
  if (!line || line->empty()) return std::nullopt;
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(line->data(), line->data() + line->size(), value);
  if (ec != std::errc{} || end != line->data() + line->size()) return std::nullopt;
  return value;
}

std::optional<bool> read_inversed(int fd) noexcept {
  char buffer[32];
  const auto line = first_line(fd, buffer);
  if (!line) return std::nullopt;
  if (*line == "inversed") return true;
  if (*line == "normal") return false;
  return std::nullopt;
}

struct Line {
  SimLine sim;
  bool active_low = false;
  bool pull_high = false;  // as last set
  bool asserted_is_high() const noexcept { return !active_low; }
};

board::Result<Line> open_line(const board::MotorLineConfig& config, const std::string& field) {
  auto sim = SimLine::open(config.chip, config.line, "motor readback: " + field);
  if (!sim) return sim.error();
  return Line{std::move(sim).value(), config.active_low};
}

}  // namespace

struct MotorReadback::Impl {
  std::optional<PwmControllerState> controller;  // a kernel PWM controller of the rig's, instead of the tree
  UniqueFd enable;
  UniqueFd duty;
  UniqueFd period;
  UniqueFd polarity;
  std::optional<Line> enable_line;
  std::optional<Line> direction_line;
  std::optional<Line> fault_line;
  bool board_inverts = false;
  bool hold_released = true;
  double full_duty_nm = 0.0;
  std::string description;

  // The PWM pin's output: the fraction of each period it is high. From the controller, its own; from the tree,
  // worked out as a controller would put it out (pin_from_tree).
  double pin_high = 0.0;
  // As last read, for a read that fails.
  std::uint64_t enable_value = 0;
  std::uint64_t duty_ns = 0;
  std::uint64_t period_ns = 0;
  bool inversed = false;
  bool enable_line_asserted = false;
  bool direction_asserted = false;
  std::uint64_t read_errors = 0;
  std::uint64_t reads = 0;

  void take(std::optional<std::uint64_t> read, std::uint64_t& into) noexcept {
    if (read) {
      into = *read;
    } else {
      ++read_errors;
    }
  }
  void take(std::optional<bool> read, bool& into) noexcept {
    if (read) {
      into = *read;
    } else {
      ++read_errors;
    }
  }
  // The tree of regular files lever-fw writes (make_fake_pwm_channel), its attributes opened; empty, or why not.
  std::string open_tree(const board::PwmMotorConfig& config) {
    auto tree = make_fake_pwm_channel(config.sysfs_root, config.pwm_chip, config.pwm_channel);
    if (!tree) return tree.error().message;
    const std::string& dir = tree.value().channel_dir;
    struct Attribute {
      const char* name;
      UniqueFd* fd;
    };
    for (const Attribute& a : {Attribute{"enable", &enable}, Attribute{"duty_cycle", &duty},
                               Attribute{"period", &period}, Attribute{"polarity", &polarity}}) {
      a.fd->reset(::open((dir + "/" + a.name).c_str(), O_RDONLY | O_CLOEXEC));
      if (!*a.fd) return "motor readback: cannot open " + dir + "/" + a.name + ": " + std::strerror(errno);
    }
    return {};
  }
  void read_controller() noexcept {
    if (const auto out = controller->read()) {
      enable_value = out->enabled ? 1 : 0;
      duty_ns = out->duty_ns;
      period_ns = out->period_ns;
      inversed = out->inversed;
      pin_high = static_cast<double>(out->pin_ppm) / kPinFullPpm;
    } else {
      ++read_errors;
    }
  }
  // The tree has no controller behind it: its pin is what the rig's lever-pwm-sim in its default mode would put
  // out. Enabled, high for duty/period (the rest of it inversed); disabled, where the kernel leaves the output
  // undefined, the worst a controller does: stopped in the high part of a period if there was one, so that a
  // program taking "disabled" for "off" is seen.
  void pin_from_tree() noexcept {
    if (enable_value == 1) {
      const double high =
          period_ns > 0 ? std::min(static_cast<double>(duty_ns) / static_cast<double>(period_ns), 1.0) : 0.0;
      pin_high = inversed ? 1.0 - high : high;
    } else if (pin_high > 0.0) {
      pin_high = 1.0;
    }
  }
  void read_tree() noexcept {
    take(read_unsigned(enable.get()), enable_value);
    take(read_unsigned(duty.get()), duty_ns);
    // The period and polarity are set when lever-fw opens the channel and never again while it runs: read
    // every 100th call once the channel has a period, which saves a third of the reads in the world's 1 kHz
    // loop. No period yet: read until there is one.
    if (reads++ % 100 == 0 || period_ns == 0) {
      take(read_unsigned(period.get()), period_ns);
      take(read_inversed(polarity.get()), inversed);
    }
    pin_from_tree();
  }
  void take_line(std::optional<Line>& line, bool& asserted) noexcept {
    if (!line) return;
    const std::optional<bool> level = line->sim.level();
    if (!level) {
      ++read_errors;
      return;
    }
    asserted = *level == line->asserted_is_high();
    // A level the pull does not give is a program driving the line: the pull takes it, and keeps it when the
    // program lets go. (On a line nobody drives the level is the pull's, so this writes nothing.)
    if (hold_released && *level != line->pull_high) {
      if (line->sim.drive(*level)) {
        line->pull_high = *level;
      } else {
        ++read_errors;
      }
    }
  }
};

board::Result<MotorReadback> MotorReadback::open(const board::PwmMotorConfig& config, ReleasedLines released) {
  if (const auto problems = config.validate(); !problems.empty())
    return board::config_error("motor readback", problems);
  auto impl = std::make_unique<Impl>();
  impl->description = "pwmchip" + std::to_string(config.pwm_chip) + "/pwm" + std::to_string(config.pwm_channel) +
                      " under " + config.sysfs_root;
  if (auto controller = PwmControllerState::find(config.sysfs_root, config.pwm_chip, config.pwm_channel)) {
    if (!*controller) return controller->error();
    impl->controller.emplace(std::move(*controller).value());
    impl->description += " (the controller's output, " + impl->controller->path() + ")";
  } else if (auto opened = impl->open_tree(config); !opened.empty()) {
    return Error{opened, EINVAL};
  }

  struct LineField {
    const char* field;
    const std::optional<board::MotorLineConfig>& config;
    std::optional<Line>& line;
  };
  for (const LineField& l : {LineField{"enable_line", config.enable_line, impl->enable_line},
                             LineField{"direction_line", config.direction_line, impl->direction_line},
                             LineField{"fault_line", config.fault_line, impl->fault_line}}) {
    if (!l.config) continue;
    auto opened = open_line(*l.config, l.field);
    if (!opened) return opened.error();
    l.line.emplace(std::move(opened).value());
    // Deasserted: a resistor's level on the driver's inputs, and the fault output not reporting.
    l.line->pull_high = !l.line->asserted_is_high();
    if (!l.line->sim.drive(l.line->pull_high)) {
      const int err = errno;
      return Error{std::string("motor readback: ") + l.field + " (" + l.line->sim.description() +
                       "): cannot set its pull: " + std::strerror(err),
                   err};
    }
    impl->description += std::string(", ") + l.field + " " + l.line->sim.description();
  }
  impl->board_inverts = config.pwm_inversed;
  impl->hold_released = released == ReleasedLines::hold;
  impl->full_duty_nm = config.gear_ratio * config.torque_constant_nm_per_a * config.full_scale_current_a;
  return MotorReadback(std::move(impl));
}

MotorReadback::MotorReadback(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
MotorReadback::MotorReadback(MotorReadback&&) noexcept = default;
MotorReadback& MotorReadback::operator=(MotorReadback&&) noexcept = default;
MotorReadback::~MotorReadback() = default;

MotorReading MotorReadback::read() noexcept {
  Impl& s = *impl_;
  if (s.controller) {
    s.read_controller();
  } else {
    s.read_tree();
  }
  s.take_line(s.enable_line, s.enable_line_asserted);
  s.take_line(s.direction_line, s.direction_asserted);

  MotorReading r;
  // The torque comes from what reaches the driver, never from the PWM's enable flag: a disabled PWM's pin may
  // hold high. The board's inverter (pwm_inversed) turns the pin over on its way, undoing the polarity PwmMotor
  // writes for it; a mismatch shows as the complement.
  r.duty = s.board_inverts ? 1.0 - s.pin_high : s.pin_high;
  r.enabled = !s.enable_line || s.enable_line_asserted;
  r.negative = s.direction_line && s.direction_asserted;
  if (r.enabled) r.torque_nm = (r.negative ? -1.0 : 1.0) * r.duty * s.full_duty_nm;
  return r;
}

bool MotorReadback::set_fault(bool asserted) noexcept {
  if (!impl_->fault_line) return false;
  Line& line = *impl_->fault_line;
  return line.sim.drive(asserted == line.asserted_is_high());
}

std::uint64_t MotorReadback::read_errors() const noexcept { return impl_->read_errors; }

const std::string& MotorReadback::description() const noexcept { return impl_->description; }

}  // namespace lever::hil::devices
