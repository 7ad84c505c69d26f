#pragma once
// A stand-in for /sys/class/pwm in a temporary directory: pwmchipN/export, and (unless the test wants to see
// the export) pwmchipN/pwmM/ with its four attributes, as regular files.
//
// A regular file is no sysfs attribute: a pwrite of "0\n" over "50000\n" leaves "0\n000\n". Every value the
// motor writes ends in a newline, so the value last written is the file's first line, which is what read()
// returns.
#include <filesystem>
#include <string>

namespace lever::test {

class PwmSysfsTree {
 public:
  // Creates <tmp>/lever-pwm-XXXXXX/class/pwm/pwmchip<chip>/export, and pwm<channel>/ when `with_channel`.
  PwmSysfsTree(unsigned chip, unsigned channel, bool with_channel = true);
  ~PwmSysfsTree();
  PwmSysfsTree(const PwmSysfsTree&) = delete;
  PwmSysfsTree& operator=(const PwmSysfsTree&) = delete;

  const std::string& root() const { return root_; }  // the sysfs_root to configure
  std::filesystem::path chip_dir() const;
  std::filesystem::path channel_dir() const;

  // The first line of an attribute of pwm<channel>/ ("duty_cycle", "enable", ...); "" when empty.
  std::string read(const std::string& attribute) const;
  std::string read_export() const;
  // Replaces an attribute's content, to see whether the motor writes it again.
  void overwrite(const std::string& attribute, const std::string& content) const;

 private:
  std::string root_;
  unsigned chip_;
  unsigned channel_;
};

}  // namespace lever::test
