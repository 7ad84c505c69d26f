#pragma once
// A Linux PWM channel's sysfs directory as regular files, for a program that drives PWM through sysfs
// (the board layer's SysfsPwm) and for the world that reads back what it wrote. The kernel would make pwmM/ when
// `M` is written to export; a regular file cannot, so the channel's directory is made up front, as a channel
// exported at boot would be found.
#include <string>

#include "lever/board/result.hpp"

namespace lever::hil::devices {

struct FakePwmChannel {
  std::string chip_dir;     // <root>/class/pwm/pwmchipN
  std::string channel_dir;  // <chip_dir>/pwmM
};

// Makes <root>/class/pwm/pwmchip<chip>/{export,unexport,npwm} and pwm<channel>/{enable,duty_cycle,period,
// polarity}. What exists already is kept as it is (a program still running has these files open and goes on
// writing to them; a channel a killed program left enabled stays enabled, as a real PWM keeps running), and
// only what is missing is made, in the state of a freshly exported channel: disabled, duty 0, period 0,
// polarity normal. Refuses a root that is /sys or under it: the real sysfs is the kernel's.
board::Result<FakePwmChannel> make_fake_pwm_channel(const std::string& root, unsigned chip, unsigned channel);

}  // namespace lever::hil::devices
