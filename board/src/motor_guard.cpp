#include "lever/board/motor_guard.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>
#include <string>

#include "motor_stop_registry.hpp"

namespace lever::board {

namespace {

Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

std::atomic<pid_t> guard_pid{0};
std::atomic<bool> guard_lost{false};
static_assert(std::atomic<pid_t>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

// The guard is this process's only child: SIGCHLD means it ended (stops and continues are not reported).
extern "C" void on_guard_ended(int) {
  const int saved_errno = errno;
  const pid_t pid = guard_pid.load();
  int status = 0;
  if (pid > 0 && ::waitpid(pid, &status, WNOHANG) == pid) {
    emergency_stop_registered_motors();
    guard_lost.store(true);
  }
  errno = saved_errno;
}

// How long start() waits for the guard to say it holds on to this process: an exec and a few system calls.
constexpr int kReadyTimeoutMs = 5000;

}  // namespace

MotorGuard::MotorGuard(pid_t pid, MotorGuardShared* shared, std::string description) noexcept
    : pid_(pid), shared_(shared), description_(std::move(description)) {}

MotorGuard::MotorGuard(MotorGuard&& other) noexcept
    : pid_(std::exchange(other.pid_, 0)),
      shared_(std::exchange(other.shared_, nullptr)),
      trips_seen_(other.trips_seen_),
      description_(std::move(other.description_)) {}

MotorGuard::~MotorGuard() {
  if (shared_ == nullptr) return;
  shared_->loop_ended.store(true);
  ::munmap(shared_, sizeof(MotorGuardShared));
}

bool MotorGuard::take_trip() noexcept {
  const std::uint64_t trips = shared_->trips.load();
  if (trips == trips_seen_) return false;
  trips_seen_ = trips;
  return true;
}

bool MotorGuard::lost() noexcept { return guard_lost.load(); }

Result<MotorGuard> MotorGuard::start(const MotorGuardConfig& config, const MotorGuardHandles& handles) {
  if (handles.duty_fd < 0 || handles.enable_fd < 0) return Error{"motor guard: no PWM files to guard", EBADF};
  if (guard_pid.load() != 0) return Error{"motor guard: one runs already (one motor per lever-fw)", EBUSY};
  UniqueFd memory(::memfd_create("lever-motor-guard", MFD_CLOEXEC));
  if (!memory) return os_error(errno, "motor guard: memfd_create");
  if (::ftruncate(memory.get(), sizeof(MotorGuardShared)) != 0) return os_error(errno, "motor guard: ftruncate");
  void* page = ::mmap(nullptr, sizeof(MotorGuardShared), PROT_READ | PROT_WRITE, MAP_SHARED, memory.get(), 0);
  if (page == MAP_FAILED) return os_error(errno, "motor guard: mmap");
  auto* shared = new (page) MotorGuardShared{};
  const auto unmap = [&] { ::munmap(page, sizeof(MotorGuardShared)); };

  int ready[2];
  if (::pipe2(ready, O_CLOEXEC) != 0) {
    unmap();
    return os_error(errno, "motor guard: pipe");
  }
  UniqueFd ready_read(ready[0]), ready_write(ready[1]);
  // Everything the child needs is made before fork: this process may have threads, and the child calls only
  // async-signal-safe functions until its exec.
  const std::string spec =
      "lever=" + std::to_string(::getpid()) + ",shared=" + std::to_string(memory.get()) +
      ",duty=" + std::to_string(handles.duty_fd) + ",enable=" + std::to_string(handles.enable_fd) +
      ",line=" + std::to_string(handles.enable_line_fd) + ",deadline_ms=" + std::to_string(config.deadline.count()) +
      ",check_ms=" + std::to_string(config.check.count()) + ",priority=" + std::to_string(config.fifo_priority) +
      ",ready=" + std::to_string(ready_write.get());
  const char* argv[] = {config.program.c_str(), "--motor-guard", spec.c_str(), nullptr};
  const int passed[] = {memory.get(), handles.duty_fd, handles.enable_fd, handles.enable_line_fd, ready_write.get()};

  const pid_t pid = ::fork();
  if (pid < 0) {
    unmap();
    return os_error(errno, "motor guard: fork");
  }
  if (pid == 0) {
    for (const int fd : passed) {
      if (fd >= 0) ::fcntl(fd, F_SETFD, 0);
    }
    sigset_t none;
    ::sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::execv(argv[0], const_cast<char* const*>(argv));
    ::_exit(127);
  }
  ready_write.reset();
  std::string answer;
  for (;;) {
    pollfd p{ready_read.get(), POLLIN, 0};
    const int n = ::poll(&p, 1, kReadyTimeoutMs);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    char buffer[256];
    const ssize_t got = ::read(ready_read.get(), buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;
    answer.append(buffer, static_cast<std::size_t>(got));
  }
  if (answer.rfind("ok", 0) != 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    unmap();
    std::string why = answer.empty() ? "it ended without a word (could " + config.program + " be run?)" : answer;
    while (!why.empty() && why.back() == '\n') why.pop_back();
    return Error{"motor guard: " + why, ECHILD};
  }
  guard_pid.store(pid);
  struct sigaction action {};
  action.sa_handler = on_guard_ended;
  ::sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART | SA_NOCLDSTOP;
  if (::sigaction(SIGCHLD, &action, nullptr) != 0) {
    const int err = errno;
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    guard_pid.store(0);
    unmap();
    return os_error(err, "motor guard: sigaction(SIGCHLD)");
  }
  on_guard_ended(SIGCHLD);  // it may have ended between its word and the handler
  std::string description = "motor guard pid " + std::to_string(pid) + ": " + answer.substr(3);
  while (!description.empty() && description.back() == '\n') description.pop_back();
  return MotorGuard(pid, shared, std::move(description));
}

}  // namespace lever::board
