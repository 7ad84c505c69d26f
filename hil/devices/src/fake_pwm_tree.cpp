#include "fake_pwm_tree.hpp"

#include <cerrno>
#include <filesystem>
#include <fstream>

namespace lever::hil::devices {

namespace {

namespace fs = std::filesystem;
using board::Error;

bool under_sys(const fs::path& path) {
  const fs::path sys("/sys");
  auto p = path.begin();
  for (auto s = sys.begin(); s != sys.end(); ++s, ++p) {
    if (p == path.end() || *p != *s) return false;
  }
  return true;
}

// Empty when `file` is a regular file now, or why not.
std::string ensure_file(const fs::path& file, const std::string& content) {
  std::error_code ec;
  const auto status = fs::symlink_status(file, ec);
  if (fs::exists(status)) {
    return fs::is_regular_file(status) ? std::string() : file.string() + " exists and is not a regular file";
  }
  std::ofstream out(file);
  out << content;
  out.close();
  return out ? std::string() : "cannot create " + file.string();
}

}  // namespace

board::Result<FakePwmChannel> make_fake_pwm_channel(const std::string& root, unsigned chip, unsigned channel) {
  if (root.empty()) return Error{"motor readback: sysfs_root is empty", EINVAL};
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(root), ec);
  if (ec) return Error{"motor readback: sysfs_root " + root + ": " + ec.message(), ec.value()};
  if (under_sys(resolved)) {
    return Error{"motor readback: sysfs_root " + root + " is " + resolved.string() +
                     ", the real sysfs: the simulated driver writes a tree of its own (point sysfs_root at a "
                     "directory of the HIL's)",
                 EPERM};
  }
  const fs::path chip_dir = resolved / "class/pwm" / ("pwmchip" + std::to_string(chip));
  const fs::path channel_dir = chip_dir / ("pwm" + std::to_string(channel));
  fs::create_directories(channel_dir, ec);
  if (ec) return Error{"motor readback: cannot create " + channel_dir.string() + ": " + ec.message(), ec.value()};

  const std::pair<fs::path, std::string> files[] = {
      {chip_dir / "export", ""},
      {chip_dir / "unexport", ""},
      {chip_dir / "npwm", std::to_string(channel + 1) + "\n"},
      {channel_dir / "enable", "0\n"},
      {channel_dir / "duty_cycle", "0\n"},
      {channel_dir / "period", "0\n"},
      {channel_dir / "polarity", "normal\n"},
  };
  for (const auto& [file, content] : files) {
    if (const std::string problem = ensure_file(file, content); !problem.empty()) {
      return Error{"motor readback: " + problem, EEXIST};
    }
  }
  return FakePwmChannel{chip_dir.string(), channel_dir.string()};
}

}  // namespace lever::hil::devices
