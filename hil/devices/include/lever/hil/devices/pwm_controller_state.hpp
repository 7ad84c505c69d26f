#pragma once
// A PWM controller of the kernel rig (lever-pwm-sim, tools/kernel-rig/pwm-sim): what the kernel's PWM core last
// programmed it with, and what its pin puts out under that, read from its hw_state attribute. The pin holds when
// the channel is unexported or its program dies, as a real PWM block keeps running; disabled, it does what the
// module's disabled_output makes it do (the kernel leaves a disabled PWM's output undefined).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::hil::devices {

struct PwmOutput {
  bool enabled = false;
  std::uint64_t period_ns = 0;
  std::uint64_t duty_ns = 0;
  bool inversed = false;
  std::uint64_t applies = 0;       // states the controller was programmed with since it was made
  std::int64_t last_apply_ns = 0;  // CLOCK_MONOTONIC of the newest
  std::uint32_t pin_ppm = 0;       // the pin's output: millionths of each period it is high
};

inline constexpr std::uint32_t kPinFullPpm = 1'000'000;  // pin_ppm of a pin high all the time

// One state the controller was programmed with (its apply_log).
struct PwmApplied {
  std::uint64_t number = 0;  // 1 for the first since the controller was made
  std::int64_t time_ns = 0;  // CLOCK_MONOTONIC
  bool enabled = false;
  std::uint64_t period_ns = 0;
  std::uint64_t duty_ns = 0;
  std::uint32_t pin_ppm = 0;  // the pin's output under it
};

class PwmControllerState {
 public:
  // <root>/class/pwm/pwmchip<chip>/device/hw_state, when that chip is a lever-pwm-sim controller; nullopt when
  // it is not one (another driver, or a tree of regular files); an error when it is one but cannot be used.
  static std::optional<board::Result<PwmControllerState>> find(const std::string& root, unsigned chip,
                                                               unsigned channel);

  // One pread and a parse, no allocation; nullopt when the attribute cannot be read or parsed.
  std::optional<PwmOutput> read() const noexcept;
  // The controller's newest states, oldest first (up to 32); empty when the log cannot be read.
  std::vector<PwmApplied> apply_log() const;
  const std::string& path() const noexcept { return path_; }

 private:
  PwmControllerState(board::UniqueFd fd, std::string path) noexcept : fd_(std::move(fd)), path_(std::move(path)) {}
  board::UniqueFd fd_;
  std::string path_;  // .../hw_state
};

}  // namespace lever::hil::devices
