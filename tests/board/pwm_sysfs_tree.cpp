#include "pwm_sysfs_tree.hpp"

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace lever::test {

namespace {

std::string first_line(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::string line;
  std::getline(in, line);
  return line;
}

void create(const std::filesystem::path& file, const std::string& content) {
  std::ofstream out(file, std::ios::trunc);
  if (!out) throw std::runtime_error("cannot create " + file.string());
  out << content;
}

}  // namespace

PwmSysfsTree::PwmSysfsTree(unsigned chip, unsigned channel, bool with_channel) : chip_(chip), channel_(channel) {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/lever-pwm-XXXXXX";
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (::mkdtemp(buffer.data()) == nullptr) throw std::runtime_error("mkdtemp " + pattern);
  root_ = buffer.data();
  std::filesystem::create_directories(chip_dir());
  create(chip_dir() / "export", "");
  create(chip_dir() / "unexport", "");
  if (with_channel) {
    std::filesystem::create_directory(channel_dir());
    // What a channel that an earlier run left running would show.
    create(channel_dir() / "enable", "1\n");
    create(channel_dir() / "duty_cycle", "123456\n");
    create(channel_dir() / "period", "1000000\n");
    create(channel_dir() / "polarity", "inversed\n");
  }
}

PwmSysfsTree::~PwmSysfsTree() {
  std::error_code ignored;
  std::filesystem::remove_all(root_, ignored);
}

std::filesystem::path PwmSysfsTree::chip_dir() const {
  return std::filesystem::path(root_) / "class/pwm" / ("pwmchip" + std::to_string(chip_));
}

std::filesystem::path PwmSysfsTree::channel_dir() const { return chip_dir() / ("pwm" + std::to_string(channel_)); }

std::string PwmSysfsTree::read(const std::string& attribute) const { return first_line(channel_dir() / attribute); }

std::string PwmSysfsTree::read_export() const { return first_line(chip_dir() / "export"); }

void PwmSysfsTree::overwrite(const std::string& attribute, const std::string& content) const {
  create(channel_dir() / attribute, content);
}

}  // namespace lever::test
