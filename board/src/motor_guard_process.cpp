// The guard process itself (lever-fw --motor-guard SPEC): see motor_guard.hpp.
#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/signalfd.h>
#include <sys/syscall.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#include "lever/board/motor_guard.hpp"
#include "motor_lines.hpp"
#include "sysfs_write.hpp"

namespace lever::board {

namespace {

struct Spec {
  long lever = -1, shared = -1, duty = -1, enable = -1, line = -1, deadline_ms = -1, check_ms = -1, priority = -1,
       ready = -1;
};

bool parse(std::string_view text, Spec& spec) {
  struct Field {
    std::string_view key;
    long* value;
  };
  const Field fields[] = {{"lever", &spec.lever},
                          {"shared", &spec.shared},
                          {"duty", &spec.duty},
                          {"enable", &spec.enable},
                          {"line", &spec.line},
                          {"ready", &spec.ready},
                          {"deadline_ms", &spec.deadline_ms},
                          {"check_ms", &spec.check_ms},
                          {"priority", &spec.priority}};
  while (!text.empty()) {
    const std::string_view item = text.substr(0, text.find(','));
    text.remove_prefix(std::min(text.size(), item.size() + 1));
    const auto eq = item.find('=');
    if (eq == std::string_view::npos) return false;
    bool known = false;
    for (const Field& f : fields) {
      if (item.substr(0, eq) != f.key) continue;
      const std::string_view number = item.substr(eq + 1);
      const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), *f.value);
      if (ec != std::errc{} || end != number.data() + number.size()) return false;
      known = true;
    }
    if (!known) return false;
  }
  return spec.lever > 1 && spec.shared >= 0 && spec.duty >= 0 && spec.enable >= 0 && spec.line >= -1 &&
         spec.ready >= 0 && spec.deadline_ms > 0 && spec.check_ms > 0 && spec.priority >= 0 && spec.priority <= 99;
}

std::int64_t monotonic_ns() noexcept {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// The defined inactive state, the driver's enable first (it cuts the bridge whatever the PWM does), then duty 0 with
// the PWM enabled. Each write is tried whatever the one before did.
void drive_off(const Spec& s) noexcept {
  if (s.line >= 0) set_line_request(static_cast<int>(s.line), false);
  write_decimal(static_cast<int>(s.duty), 0);
  write_decimal(static_cast<int>(s.enable), 1);
}

void say(const std::string& text) {
  const std::string line = "lever-fw: motor guard: " + text + "\n";
  [[maybe_unused]] const auto ignored = ::write(STDERR_FILENO, line.data(), line.size());
}

void answer(int ready, const std::string& text) {
  const std::string line = text + "\n";
  [[maybe_unused]] const auto ignored = ::write(ready, line.data(), line.size());
  ::close(ready);
}

}  // namespace

int run_motor_guard(const char* spec_text) {
  Spec s;
  if (spec_text == nullptr || !parse(spec_text, s)) {
    say(std::string("cannot read its spec \"") + (spec_text ? spec_text : "") + "\" (it is started by lever-fw)");
    return 2;
  }
  const int ready = static_cast<int>(s.ready);
  const auto lever = static_cast<pid_t>(s.lever);
  const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, lever, 0));
  if (pidfd < 0) {
    const int err = errno;
    answer(ready, std::string("cannot hold on to the lever: pidfd_open: ") + std::strerror(err));
    return 1;
  }
  // Opened after the lever may have ended and its pid been reused: only its child's parent is surely the lever.
  if (::getppid() != lever) {
    drive_off(s);
    answer(ready, "the lever ended before its guard started");
    return 1;
  }
  std::string notes;
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer's shadow is terabytes of reserved address space, which mlockall would try to fault in.
  notes += ", memory not locked (AddressSanitizer build)";
#else
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) notes += std::string(", warning: mlockall: ") + std::strerror(errno);
#endif
  // Memory is locked before the priority is raised: mlockall faults in everything the lever mapped before the
  // fork, and at the guard's priority that would take the CPU from any loop on the board.
  if (s.priority > 0) {
    sched_param param{};
    param.sched_priority = static_cast<int>(s.priority);
    if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
      notes += std::string(", warning: SCHED_FIFO ") + std::to_string(s.priority) + " refused (" +
               std::strerror(errno) + "): a loop spinning at its priority could starve it";
    }
  }
  void* page =
      ::mmap(nullptr, sizeof(MotorGuardShared), PROT_READ | PROT_WRITE, MAP_SHARED, static_cast<int>(s.shared), 0);
  if (page == MAP_FAILED) {
    const int err = errno;
    drive_off(s);
    answer(ready, std::string("mmap of the shared page: ") + std::strerror(err));
    return 1;
  }
  auto* shared = static_cast<MotorGuardShared*>(page);
  // The service manager's stop signals go to every process of the unit: the lever stops its motor and ends, and the
  // guard, which must outlive it, keeps watching until then.
  sigset_t stops;
  ::sigemptyset(&stops);
  for (const int sig : {SIGTERM, SIGINT, SIGHUP, SIGQUIT}) ::sigaddset(&stops, sig);
  ::sigprocmask(SIG_BLOCK, &stops, nullptr);
  const int signals = ::signalfd(-1, &stops, SFD_CLOEXEC);
  const int timer = ::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
  itimerspec every{};
  every.it_interval.tv_nsec = s.check_ms % 1000 * 1'000'000;
  every.it_interval.tv_sec = s.check_ms / 1000;
  every.it_value = every.it_interval;
  if (signals < 0 || timer < 0 || ::timerfd_settime(timer, 0, &every, nullptr) != 0) {
    const int err = errno;
    drive_off(s);
    answer(ready, std::string("signalfd or timerfd: ") + std::strerror(err));
    return 1;
  }
  answer(ready, "ok deadline " + std::to_string(s.deadline_ms) + " ms, checked every " + std::to_string(s.check_ms) +
                    " ms, " +
                    (s.priority > 0 ? "SCHED_FIFO " + std::to_string(s.priority) : std::string("no priority")) +
                    (s.line >= 0 ? "" : ", no enable line") + notes);

  const std::int64_t deadline_ns = s.deadline_ms * 1'000'000;
  bool tripped = false;
  for (;;) {
    pollfd fds[3] = {{pidfd, POLLIN, 0}, {timer, POLLIN, 0}, {signals, POLLIN, 0}};
    if (::poll(fds, 3, -1) < 0) {
      if (errno == EINTR) continue;
      drive_off(s);
      say(std::string("poll: ") + std::strerror(errno) + ": motor off, the guard ends");
      return 1;
    }
    if (fds[0].revents != 0) {
      drive_off(s);
      say("the lever (pid " + std::to_string(lever) + ") ended: motor off (enable line low, duty 0)");
      return 0;
    }
    if (fds[2].revents != 0) {
      signalfd_siginfo info{};
      [[maybe_unused]] const auto ignored = ::read(signals, &info, sizeof info);
    }
    if (fds[1].revents == 0) continue;
    std::uint64_t expirations = 0;
    [[maybe_unused]] const auto ignored = ::read(timer, &expirations, sizeof expirations);
    const std::int64_t last = shared->last_step_ns.load();
    if (last == 0 || shared->loop_ended.load()) continue;
    const std::int64_t age = monotonic_ns() - last;
    if (age <= deadline_ns) {
      tripped = false;
      continue;
    }
    if (tripped) continue;
    drive_off(s);
    tripped = true;
    shared->trips.fetch_add(1);
    say("the lever's loop has not stepped for " + std::to_string(age / 1'000'000) + " ms (deadline " +
        std::to_string(s.deadline_ms) + "): motor off (enable line low, duty 0)");
  }
}

}  // namespace lever::board
