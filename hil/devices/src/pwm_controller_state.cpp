#include "lever/hil/devices/pwm_controller_state.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <string_view>

namespace lever::hil::devices {

namespace {

// Parses the next space-separated unsigned number of `text` from `at`.
std::optional<std::uint64_t> next_number(std::string_view text, std::size_t& at) noexcept {
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data() + at, text.data() + text.size(), value);
  if (ec != std::errc{}) return std::nullopt;
  at = static_cast<std::size_t>(end - text.data());
  if (at < text.size() && text[at] == ' ') ++at;
  return value;
}

}  // namespace

std::optional<board::Result<PwmControllerState>> PwmControllerState::find(const std::string& root, unsigned chip,
                                                                          unsigned channel) {
  const std::string path = root + "/class/pwm/pwmchip" + std::to_string(chip) + "/device/hw_state";
  if (::access(path.c_str(), F_OK) != 0) return std::nullopt;
  if (channel != 0) {
    return board::Result<PwmControllerState>(board::Error{"motor readback: pwmchip" + std::to_string(chip) +
                                                              " is a lever-pwm-sim controller, which has channel 0 "
                                                              "only (pwm_channel is " +
                                                              std::to_string(channel) + ")",
                                                          EINVAL});
  }
  board::UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd) {
    const int err = errno;
    return board::Result<PwmControllerState>(
        board::Error{"motor readback: cannot open " + path + ": " + std::strerror(err), err});
  }
  return board::Result<PwmControllerState>(PwmControllerState(std::move(fd), path));
}

std::optional<PwmOutput> PwmControllerState::read() const noexcept {
  char buffer[96];
  const ssize_t got = ::pread(fd_.get(), buffer, sizeof buffer, 0);
  if (got <= 0) return std::nullopt;
  // "enabled period_ns duty_ns polarity applies last_apply_ns pin_ppm\n"
  const std::string_view text(buffer, static_cast<std::size_t>(got));
  std::size_t at = 0;
  const auto enabled = next_number(text, at);
  const auto period = next_number(text, at);
  const auto duty = next_number(text, at);
  if (!enabled || !period || !duty || *enabled > 1) return std::nullopt;
  const std::string_view rest = text.substr(at);
  PwmOutput out{*enabled == 1, *period, *duty, false, 0, 0, 0};
  if (rest.starts_with("inversed ")) {
    out.inversed = true;
  } else if (!rest.starts_with("normal ")) {
    return std::nullopt;
  }
  at += rest.find(' ') + 1;
  const auto applies = next_number(text, at);
  const auto last = next_number(text, at);
  const auto pin = next_number(text, at);
  if (!applies || !last || !pin || *pin > kPinFullPpm) return std::nullopt;
  out.applies = *applies;
  out.last_apply_ns = static_cast<std::int64_t>(*last);
  out.pin_ppm = static_cast<std::uint32_t>(*pin);
  return out;
}

std::vector<PwmApplied> PwmControllerState::apply_log() const {
  std::vector<PwmApplied> log;
  const std::string path = path_.substr(0, path_.rfind('/')) + "/apply_log";
  const board::UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd) return log;
  char buffer[4096];
  const ssize_t got = ::read(fd.get(), buffer, sizeof buffer);
  if (got <= 0) return log;
  const std::string_view text(buffer, static_cast<std::size_t>(got));
  std::size_t line_start = 0;
  while (line_start < text.size()) {
    const std::size_t line_end = text.find('\n', line_start);
    if (line_end == std::string_view::npos) break;
    const std::string_view line = text.substr(line_start, line_end - line_start + 1);
    line_start = line_end + 1;
    std::size_t at = 0;
    const auto number = next_number(line, at);
    const auto time = next_number(line, at);
    const auto enabled = next_number(line, at);
    const auto period = next_number(line, at);
    const auto duty = next_number(line, at);
    const auto pin = next_number(line, at);
    if (!number || !time || !enabled || !period || !duty || !pin || *pin > kPinFullPpm) return {};
    log.push_back(
        {*number, static_cast<std::int64_t>(*time), *enabled == 1, *period, *duty, static_cast<std::uint32_t>(*pin)});
  }
  return log;
}

}  // namespace lever::hil::devices
