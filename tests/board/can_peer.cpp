#include "can_peer.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace lever::test {

namespace {

constexpr const char* kMarkerId = "7FF";

pid_t spawn(const std::vector<std::string>& argv, const std::string& stdout_path, int stdout_fd = -1) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!stdout_path.empty()) {
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  } else if (stdout_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, stdout_fd, STDOUT_FILENO);
  }
  pid_t pid = -1;
  const int rc = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot run " + argv[0]);
  return pid;
}

int wait_for(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("waitpid failed");
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

int run(const std::vector<std::string>& argv) { return wait_for(spawn(argv, {})); }

std::string output_of(const std::vector<std::string>& argv) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = spawn(argv, {}, fds[1]);
  ::close(fds[1]);
  std::string out;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n > 0) {
      out.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  ::close(fds[0]);
  wait_for(pid);
  return out;
}

Background::Background(const std::vector<std::string>& argv, const std::string& stdout_path)
    : pid_(spawn(argv, stdout_path)) {}

Background::~Background() { stop(); }

int Background::wait() {
  const int code = wait_for(pid_);
  pid_ = -1;
  return code;
}

void Background::stop() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  wait_for(pid_);
  pid_ = -1;
}

std::vector<LoggedFrame> read_candump_log(const std::string& path) {
  std::vector<LoggedFrame> frames;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string time, interface, frame;
    if (!(fields >> time >> interface >> frame)) continue;
    const auto hash = frame.find('#');
    if (hash == std::string::npos) continue;
    frames.push_back({interface, frame.substr(0, hash), frame.substr(hash + 1)});
  }
  return frames;
}

Candump::Candump(const std::string& interface, const std::string& log_path)
    : interface_(interface),
      path_(log_path),
      // stdbuf: candump's stdout into a file is block-buffered, and start() must see the markers as they come.
      process_({"stdbuf", "-oL", "candump", "-L", "-r", "8388608", interface}, log_path) {
  for (int attempt = 0; attempt < 600; ++attempt) {
    run({"cansend", interface_, std::string(kMarkerId) + "#"});
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    for (const auto& f : read_candump_log(path_)) {
      if (f.id == kMarkerId) return;
    }
  }
  throw std::runtime_error("candump on " + interface + " logged none of 600 marker frames");
}

std::vector<LoggedFrame> Candump::stop() {
  process_.stop();
  std::vector<LoggedFrame> frames;
  for (auto& f : read_candump_log(path_)) {
    if (f.id != kMarkerId) frames.push_back(std::move(f));
  }
  return frames;
}

}  // namespace lever::test
