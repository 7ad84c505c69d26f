#pragma once
// The independent side of the CAN backend's guest tests: can-utils (candump, cansend, cangen) and iproute2
// (ip, tc), run as child processes. Nothing here uses the code under test.
#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lever::test {

// Runs a command to its end; its exit code (128 + signal when killed). stdout and stderr are the test's.
int run(const std::vector<std::string>& argv);
// Runs a command to its end and returns its stdout.
std::string output_of(const std::vector<std::string>& argv);

// A command in the background, until stop() or destruction (SIGTERM, then waited for).
class Background {
 public:
  // stdout goes to `stdout_path` when given.
  explicit Background(const std::vector<std::string>& argv, const std::string& stdout_path = {});
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;
  ~Background();
  int wait();  // to its own end; its exit code
  void stop();
  bool running() const { return pid_ > 0; }

 private:
  pid_t pid_ = -1;
};

// One line of a candump -L log: "(sec.usec) iface ID#DATA" (ID#R for a remote frame).
struct LoggedFrame {
  std::string interface;
  std::string id;    // as candump writes it: 3 hex digits for standard frames, 8 for extended ones
  std::string data;  // hex, upper case; "R" for a remote frame
};

// candump -L on one interface, line-buffered into a file, with a receive buffer large enough not to lose
// frames in a flood. start() returns once candump has shown it is listening: it sends marker frames of its
// own (id 0x7FF, a foreign id to the lever protocol) until one appears in the log.
class Candump {
 public:
  Candump(const std::string& interface, const std::string& log_path);
  std::vector<LoggedFrame> stop();  // every frame logged, markers left out

 private:
  std::string interface_, path_;
  Background process_;
};

std::vector<LoggedFrame> read_candump_log(const std::string& path);

}  // namespace lever::test
