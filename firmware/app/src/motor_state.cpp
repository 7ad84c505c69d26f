#include "lever/app/motor_state.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "lever/board/unique_fd.hpp"

namespace lever::app {
namespace {

constexpr const char* kWriter = "writer";

std::string toml_string(const std::string& s) {
  std::ostringstream out;
  out << toml::value<std::string>(s);
  return out.str();
}

}  // namespace

MotorStateWriter this_run() {
  MotorStateWriter w;
  if (const char* id = std::getenv("INVOCATION_ID")) w.invocation_id = id;
  std::ifstream boot("/proc/sys/kernel/random/boot_id");
  std::getline(boot, w.boot_id);
  w.pid = ::getpid();
  return w;
}

std::string write_motor_state(const std::string& path, const FwConfig& config) {
  const auto run = this_run();
  const std::string text = fmt::format(
      "# lever-fw: the motor this lever opened, for lever-fw --motor-off (docs/board-motor.md)\n"
      "[{}]\ninvocation_id = {}  # $INVOCATION_ID: the unit's run (\"\": none)\nboot_id = {}\npid = {}\n\n{}",
      kWriter, toml_string(run.invocation_id), toml_string(run.boot_id), run.pid, motor_keys_toml(config));
  const std::string temporary = path + ".new";
  const auto failed = [&](const char* what) {
    const std::string why = std::strerror(errno);
    ::unlink(temporary.c_str());
    return std::string("cannot ") + what + " " + path + ": " + why;
  };
  {
    board::UniqueFd fd(::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644));
    if (!fd) return failed("write");
    std::size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = ::write(fd.get(), text.data() + written, text.size() - written);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return failed("write");
      written += static_cast<std::size_t>(n);
    }
    if (::fsync(fd.get()) != 0) return failed("write");
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) return failed("write");
  return {};
}

MotorState read_motor_state(const std::string& path) {
  MotorState out;
  if (::access(path.c_str(), F_OK) != 0 && errno == ENOENT) return out;
  out.found = true;
  auto parsed = program::ConfigSchema::parse_file(path);
  if (!parsed.error.empty()) {
    out.problems.push_back(parsed.error);
    return out;
  }
  std::string missing;
  const auto* writer = parsed.table[kWriter].as_table();
  const auto text = [&](const char* key, std::string& value) {
    const auto* v = writer != nullptr ? writer->get_as<std::string>(key) : nullptr;
    if (v == nullptr) missing += fmt::format("{}{}.{}", missing.empty() ? "" : ", ", kWriter, key);
    if (v != nullptr) value = v->get();
  };
  text("invocation_id", out.writer.invocation_id);
  text("boot_id", out.writer.boot_id);
  const auto* pid = writer != nullptr ? writer->get_as<std::int64_t>("pid") : nullptr;
  if (pid == nullptr) missing += fmt::format("{}{}.pid", missing.empty() ? "" : ", ", kWriter);
  if (pid != nullptr) out.writer.pid = pid->get();
  if (!missing.empty())
    out.problems.push_back(fmt::format("{}: {}: missing; a state names the run that wrote it", path, missing));
  parsed.table.erase(kWriter);
  auto keys = motor_keys_from(parsed.table, path, MotorKeysRequired::every_key);
  out.problems.insert(out.problems.end(), keys.problems.begin(), keys.problems.end());
  if (out.problems.empty()) out.motor = keys.motor;
  return out;
}

}  // namespace lever::app
