#include "sysfs_pwm.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <optional>
#include <thread>

#include "sysfs_write.hpp"

namespace lever::board {

namespace {

Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

bool exists(const std::string& path) { return ::access(path.c_str(), F_OK) == 0; }

// Non-blocking: a FIFO where an attribute should be (a test tree, a wrong sysfs_root) must not hang the open;
// pwrite on it then fails (ESPIPE) like any write that does not take.
UniqueFd open_for_write(const std::string& path, int access = O_WRONLY) {
  return UniqueFd(::open(path.c_str(), access | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
}

// The decimal an attribute holds (its first line: a test's regular file may keep the tail of a longer value).
std::optional<std::uint64_t> read_decimal(int fd) noexcept {
  char buffer[32];
  const ssize_t got = ::pread(fd, buffer, sizeof buffer, 0);
  if (got <= 0) return std::nullopt;
  const char* const end = buffer + got;
  std::uint64_t value = 0;
  const auto [last, ec] = std::from_chars(buffer, end, value);
  if (ec != std::errc{} || (last != end && *last != '\n')) return std::nullopt;
  return value;
}

// The kernel makes pwmM/ during the export write, but udev may still be changing its attributes' owner and
// mode for a while after; they are ready when they can be opened for writing.
bool wait_for_attributes(const std::string& dir, std::uint32_t timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    if (::access((dir + "/enable").c_str(), W_OK) == 0 && ::access((dir + "/duty_cycle").c_str(), W_OK) == 0) {
      return true;
    }
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

}  // namespace

SysfsPwm::SysfsPwm(UniqueFd duty, UniqueFd enable, std::string description) noexcept
    : duty_(std::move(duty)), enable_(std::move(enable)), description_(std::move(description)) {}

Result<SysfsPwm> SysfsPwm::open(const PwmMotorConfig& config) {
  const std::string chip_name = "pwmchip" + std::to_string(config.pwm_chip);
  const std::string channel_name = "pwm" + std::to_string(config.pwm_channel);
  const std::string chip_dir = config.sysfs_root + "/class/pwm/" + chip_name;
  const std::string dir = chip_dir + "/" + channel_name;
  const std::string name = chip_name + "/" + channel_name;
  if (!exists(chip_dir)) {
    const int err = errno;
    return os_error(err, "motor PWM: no " + chip_dir + " (ls " + config.sysfs_root + "/class/pwm shows the chips)");
  }
  if (!exists(dir)) {
    const UniqueFd exporter = open_for_write(chip_dir + "/export");
    if (!exporter) {
      const int err = errno;
      return os_error(err, "motor PWM: cannot open " + chip_dir + "/export");
    }
    if (!write_decimal(exporter.get(), config.pwm_channel)) {
      const int err = errno;
      return os_error(err, "motor PWM: cannot export " + name + (err == EBUSY ? " (a kernel driver holds it?)" : ""));
    }
  }
  if (!wait_for_attributes(dir, config.export_timeout_ms)) {
    return Error{"motor PWM: " + dir + "/enable and duty_cycle not writable " +
                     std::to_string(config.export_timeout_ms) +
                     " ms after the export (no such channel, or no permission)",
                 EACCES};
  }

  UniqueFd enable = open_for_write(dir + "/enable", O_RDWR);  // read back by enable_as_written()
  UniqueFd duty = open_for_write(dir + "/duty_cycle");
  UniqueFd period(::open((dir + "/period").c_str(), O_RDWR | O_CLOEXEC));
  UniqueFd polarity = open_for_write(dir + "/polarity");
  struct Opened {
    const char* attribute;
    const UniqueFd* fd;
  };
  for (const Opened& o : {Opened{"enable", &enable}, Opened{"duty_cycle", &duty}, Opened{"period", &period},
                          Opened{"polarity", &polarity}}) {
    if (!*o.fd) {
      const int err = errno;
      return os_error(err, "motor PWM: cannot open " + dir + "/" + o.attribute);
    }
  }
  // The kernel's PWM core refuses every state with period 0, and a freshly exported channel has period 0 on
  // many controllers: then the period goes first. A channel found exported may be running: duty 0 before the
  // disable, so that a controller that stops a disabled pin where it is (the kernel leaves a disabled output
  // undefined) stops it at the inactive level. Disabled next, because controllers change the polarity only while
  // disabled, and duty 0 before the period, because a period shorter than the duty in force is refused. Then
  // enabled at duty 0: the one state whose output the kernel defines as inactive, whatever the polarity.
  const auto failed = [&](const char* attribute, const std::string& value) {
    const int err = errno;
    return os_error(err, "motor PWM: cannot write " + value + " to " + dir + "/" + attribute);
  };
  const std::optional<std::uint64_t> period_in_force = read_decimal(period.get());
  if (!period_in_force) return os_error(EIO, "motor PWM: cannot read a period from " + dir + "/period");
  if (*period_in_force == 0 && !write_decimal(period.get(), config.period_ns)) {
    return failed("period", std::to_string(config.period_ns));
  }
  if (!write_decimal(duty.get(), 0)) return failed("duty_cycle", "0");
  if (!write_decimal(enable.get(), 0)) return failed("enable", "0");
  if (!write_decimal(period.get(), config.period_ns)) return failed("period", std::to_string(config.period_ns));
  const char* polarity_text = config.pwm_inversed ? "inversed" : "normal";
  if (!write_text(polarity.get(), polarity_text)) return failed("polarity", polarity_text);
  if (!write_decimal(enable.get(), 1)) return failed("enable", "1");

  SysfsPwm pwm(std::move(duty), std::move(enable), name);
  pwm.duty_written_ = 0;
  pwm.enabled_written_ = true;
  return pwm;
}

bool SysfsPwm::set_duty_ns(std::uint32_t ns) noexcept {
  if (duty_written_ == ns) return true;
  if (!write_decimal(duty_.get(), ns)) {
    duty_written_.reset();
    return false;
  }
  duty_written_ = ns;
  return true;
}

bool SysfsPwm::set_enabled(bool enabled) noexcept {
  if (enabled_written_ == enabled) return true;
  if (!write_decimal(enable_.get(), enabled ? 1 : 0)) {
    enabled_written_.reset();
    return false;
  }
  enabled_written_ = enabled;
  return true;
}

bool SysfsPwm::enable_as_written() noexcept {
  if (!enabled_written_) return true;
  const std::optional<std::uint64_t> in_force = read_decimal(enable_.get());
  if (in_force && *in_force == (*enabled_written_ ? 1u : 0u)) return true;
  enabled_written_.reset();
  return false;
}

void SysfsPwm::stop() noexcept {
  duty_written_.reset();
  enabled_written_.reset();
  set_duty_ns(0);
  set_enabled(true);
}

}  // namespace lever::board
