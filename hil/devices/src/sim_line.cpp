#include "sim_line.hpp"

#include <fcntl.h>
#include <gpiod.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <memory>

namespace lever::hil::devices {

namespace {

using board::Error;

struct ChipClose {
  void operator()(gpiod_chip* chip) const noexcept { gpiod_chip_close(chip); }
};
using ChipPtr = std::unique_ptr<gpiod_chip, ChipClose>;

// As the board layer's encoder and motor find a chip: a path, a gpiochipN name, else a label. Never a bare number,
// which libgpiod's own lookup would take too: the device must find exactly the chip the board's program does.
ChipPtr open_chip(const std::string& chip) {
  if (chip.empty()) {
    errno = EINVAL;
    return nullptr;
  }
  if (chip.front() == '/') return ChipPtr(gpiod_chip_open(chip.c_str()));
  if (chip.rfind("gpiochip", 0) == 0) {
    if (gpiod_chip* c = gpiod_chip_open_by_name(chip.c_str())) return ChipPtr(c);
  }
  return ChipPtr(gpiod_chip_open_by_label(chip.c_str()));
}

// gpio-sim puts its per-line attributes under the platform device it creates for each chip.
std::optional<std::filesystem::path> sim_chip_dir(const std::string& chip_name) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/sys/devices/platform", ec)) {
    if (entry.path().filename().string().rfind("gpio-sim.", 0) != 0) continue;
    const auto dir = entry.path() / chip_name;
    if (std::filesystem::is_directory(dir, ec)) return dir;
  }
  return std::nullopt;
}

}  // namespace

board::Result<SimLine> SimLine::open(const std::string& chip, const board::LineRef& line, const std::string& field) {
  const std::string what = field + " (" + line.describe() + " on \"" + chip + "\")";
  const ChipPtr handle = open_chip(chip);
  if (!handle) {
    const int err = errno;
    return Error{field + ": cannot open chip \"" + chip + "\": " + std::strerror(err), err};
  }
  gpiod_line* found = line.is_offset() ? gpiod_chip_get_line(handle.get(), line.offset_value())
                                       : gpiod_chip_find_line(handle.get(), line.name_value().c_str());
  if (found == nullptr) return Error{what + ": no such line on " + gpiod_chip_name(handle.get()), ENOENT};
  const std::string chip_name = gpiod_chip_name(handle.get());
  const auto dir = sim_chip_dir(chip_name);
  if (!dir) {
    return Error{what + ": " + chip_name + " is not a gpio-sim chip (no /sys/devices/platform/gpio-sim.*/" + chip_name +
                     "/): the simulated devices drive lines only through gpio-sim",
                 ENODEV};
  }
  SimLine sim;
  sim.offset_ = gpiod_line_offset(found);
  const std::string line_dir = (*dir / ("sim_gpio" + std::to_string(sim.offset_))).string();
  sim.value_.reset(::open((line_dir + "/value").c_str(), O_RDONLY | O_CLOEXEC));
  if (!sim.value_) {
    const int err = errno;
    return Error{what + ": cannot open " + line_dir + "/value: " + std::strerror(err), err};
  }
  sim.pull_.reset(::open((line_dir + "/pull").c_str(), O_WRONLY | O_CLOEXEC));
  if (!sim.pull_) {
    const int err = errno;
    return Error{what + ": cannot open " + line_dir + "/pull: " + std::strerror(err), err};
  }
  sim.chip_description_ = chip_name + " [" + gpiod_chip_label(handle.get()) + "]";
  sim.description_ = sim.chip_description_ + " " + std::to_string(sim.offset_);
  return sim;
}

std::optional<bool> SimLine::level() const noexcept {
  char buffer[4];
  const ssize_t got = ::pread(value_.get(), buffer, sizeof buffer, 0);
  if (got < 1 || (buffer[0] != '0' && buffer[0] != '1')) return std::nullopt;
  return buffer[0] == '1';
}

bool SimLine::drive(bool high) noexcept {
  const char* text = high ? "pull-up" : "pull-down";
  const auto length = static_cast<ssize_t>(std::strlen(text));
  return ::pwrite(pull_.get(), text, static_cast<std::size_t>(length), 0) == length;
}

}  // namespace lever::hil::devices
