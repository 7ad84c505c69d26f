#include "lever/board/pwm_motor_config.hpp"

#include <cmath>
#include <string>

#include "gpio_chip.hpp"

namespace lever::board {

namespace {

// Faster than a PWM controller's usual clock allows a useful resolution; slower than the 1 ms control tick,
// a torque would not be applied within the tick that computed it.
constexpr std::uint32_t kMinPeriodNs = 1'000;
constexpr std::uint32_t kMaxPeriodNs = 1'000'000;
constexpr std::uint32_t kMaxExportTimeoutMs = 10'000;

std::string number(double v) {
  std::string s = std::to_string(v);
  s.erase(s.find_last_not_of('0') + 1);
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

void check_positive(std::vector<std::string>& problems, const char* field, double value) {
  if (!std::isfinite(value) || value <= 0.0)
    problems.push_back(std::string(field) + ": " + number(value) + ", must be above 0");
}

void check_line(std::vector<std::string>& problems, const char* field, const std::optional<MotorLineConfig>& line) {
  if (!line) return;
  if (line->chip.empty()) {
    problems.push_back(std::string(field) + ".chip: empty (a path /dev/gpiochipN, a name gpiochipN, or a label)");
  }
  if (!line->line.is_offset() && line->line.name_value().empty()) {
    problems.push_back(std::string(field) + ".line: empty name");
  }
}

bool same_line(const std::optional<MotorLineConfig>& a, const std::optional<MotorLineConfig>& b) {
  return a && b && a->chip == b->chip && a->line == b->line;
}

}  // namespace

std::vector<std::string> PwmMotorConfig::validate() const {
  std::vector<std::string> problems;
  if (sysfs_root.empty()) problems.emplace_back("sysfs_root: empty (the kernel's is /sys)");
  if (period_ns < kMinPeriodNs || period_ns > kMaxPeriodNs) {
    problems.push_back("period_ns: " + std::to_string(period_ns) + ", must be within " + std::to_string(kMinPeriodNs) +
                       " to " + std::to_string(kMaxPeriodNs) + " (1 MHz to 1 kHz: the PWM must cycle within a tick)");
  }
  if (export_timeout_ms > kMaxExportTimeoutMs) {
    problems.push_back("export_timeout_ms: " + std::to_string(export_timeout_ms) + ", at most " +
                       std::to_string(kMaxExportTimeoutMs));
  }
  check_positive(problems, "torque_constant_nm_per_a", torque_constant_nm_per_a);
  check_positive(problems, "gear_ratio", gear_ratio);
  check_positive(problems, "full_scale_current_a", full_scale_current_a);
  if (!(max_duty > 0.0 && max_duty <= 1.0)) {
    problems.push_back("max_duty: " + number(max_duty) + ", must be above 0 and at most 1 (a fraction of the period)");
  }
  if (!std::isfinite(deadband_nm) || deadband_nm < 0.0) {
    problems.push_back("deadband_nm: " + number(deadband_nm) + ", must be 0 or more");
  }
  check_line(problems, "enable_line", enable_line);
  check_line(problems, "direction_line", direction_line);
  check_line(problems, "fault_line", fault_line);
  if (same_line(enable_line, direction_line)) problems.emplace_back("direction_line: the same line as enable_line");
  if (same_line(enable_line, fault_line)) problems.emplace_back("fault_line: the same line as enable_line");
  if (same_line(direction_line, fault_line)) problems.emplace_back("fault_line: the same line as direction_line");
  if (!direction_line && !positive_torque_only) {
    problems.emplace_back(
        "direction_line: none, so a negative torque could not be driven (set positive_torque_only to accept that)");
  }
  if (direction_line && positive_torque_only) {
    problems.emplace_back("positive_torque_only: set, yet direction_line is given (which one is meant?)");
  }
  if (consumer.empty()) problems.emplace_back("consumer: empty (gpioinfo would show the lines as unnamed users)");
  if (consumer.size() > kMaxGpioConsumer) {
    problems.push_back("consumer: " + std::to_string(consumer.size()) + " characters, the kernel keeps " +
                       std::to_string(kMaxGpioConsumer));
  }
  return problems;
}

}  // namespace lever::board
