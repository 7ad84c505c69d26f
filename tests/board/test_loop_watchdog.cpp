// The loop watchdog against the service manager's notify protocol. systemd cannot run as a service manager on the
// build machines (PID 1 is not systemd; `systemd --user` refuses: "Trying to run as user instance, but the system
// has not been booted with systemd"), so the test is the manager: it listens on the NOTIFY_SOCKET it hands the
// code under test, with WATCHDOG_USEC set as systemd sets it for WatchdogSec=200ms, and does on a missed
// WatchdogSec what systemd does: SIGABRT (WatchdogSignal=), then SIGCONT. What it checks is lever-fw's side:
// READY=1 once the loop has advanced, WATCHDOG=1 only while it advances, and a loop stuck in a step (or a
// stopped process) getting its motor off within WatchdogSec + the check interval.
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "lever/board/loop_watchdog.hpp"
#include "lever/board/monotonic_clock.hpp"
#include "lever/board/motor_stop_signals.hpp"
#include "lever/board/pwm_motor.hpp"
#include "lever/board/realtime_loop.hpp"
#include "pwm_sysfs_tree.hpp"

using namespace std::chrono_literals;
using lever::board::LoopWatchdog;
using lever::board::RealtimeLoop;
using Clock = std::chrono::steady_clock;

namespace {

constexpr auto kWatchdogSec = 200ms;  // as lever-fw@.service sets it

// A datagram socket where the code under test sends its notifications, and the environment that says so.
class NotifyListener {
 public:
  NotifyListener() {
    dir_ = std::filesystem::temp_directory_path() / ("lever-notify-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "notify").string();
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    REQUIRE(fd_ >= 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, path_.c_str(), sizeof address.sun_path - 1);
    ::unlink(path_.c_str());
    REQUIRE(::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
    // The kernel stamps each message as it is queued, in the sender's time: when a feed was sent does not depend
    // on when this (shared, busy) machine lets the listener read it. SO_TIMESTAMP (microseconds): qemu-user,
    // which runs these tests for arm64, translates it and refuses SO_TIMESTAMPNS.
    const int on = 1;
    REQUIRE(::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) == 0);
  }
  ~NotifyListener() {
    ::close(fd_);
    std::filesystem::remove_all(dir_);
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
    ::unsetenv("WATCHDOG_PID");
  }
  NotifyListener(const NotifyListener&) = delete;
  NotifyListener& operator=(const NotifyListener&) = delete;

  // The environment systemd gives a Type=notify service with WatchdogSec=, for process `pid`.
  void export_for(pid_t pid) const {
    ::setenv("NOTIFY_SOCKET", path_.c_str(), 1);
    ::setenv("WATCHDOG_USEC", std::to_string(std::chrono::microseconds(kWatchdogSec).count()).c_str(), 1);
    ::setenv("WATCHDOG_PID", std::to_string(pid).c_str(), 1);
  }

  struct Message {
    std::string text;
    std::int64_t sent_realtime_ns = 0;  // CLOCK_REALTIME, the kernel's stamp
  };

  // The next message within `timeout`, none when nothing came.
  std::optional<Message> receive_stamped(std::chrono::milliseconds timeout) const {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return std::nullopt;
    char buffer[512];
    iovec data{buffer, sizeof buffer};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval))];
    msghdr header{};
    header.msg_iov = &data;
    header.msg_iovlen = 1;
    header.msg_control = control;
    header.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_, &header, 0);
    if (n <= 0) return std::nullopt;
    Message message{std::string(buffer, static_cast<std::size_t>(n))};
    for (cmsghdr* c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
        timeval stamp{};
        std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
        message.sent_realtime_ns = (std::int64_t{stamp.tv_sec} * 1'000'000 + stamp.tv_usec) * 1'000;
      }
    }
    return message;
  }

  std::optional<std::string> receive(std::chrono::milliseconds timeout) const {
    auto message = receive_stamped(timeout);
    if (!message) return std::nullopt;
    return std::move(message->text);
  }

 private:
  std::filesystem::path dir_;
  std::string path_;
  int fd_ = -1;
};

bool contains(const std::string& message, const char* field) { return message.find(field) != std::string::npos; }

}  // namespace

TEST_CASE("loop watchdog: READY=1 once the loop runs, WATCHDOG=1 only while it advances", "[board][watchdog]") {
  NotifyListener manager;
  manager.export_for(::getpid());
  auto opened = LoopWatchdog::open({});
  REQUIRE(opened.ok());
  LoopWatchdog& watchdog = opened.value();
  CHECK(watchdog.service_interval() == kWatchdogSec);
  CHECK(watchdog.check_interval() == 50ms);
  CHECK(watchdog.kill_bound() == 250ms);

  // Nothing before the loop's first step: not ready, nothing fed.
  CHECK_FALSE(manager.receive(300ms).has_value());

  std::atomic<bool> advancing{true}, done{false};
  std::thread loop([&] {
    std::uint64_t tick = 0;
    while (!done) {
      if (advancing) watchdog.advanced(++tick);
      std::this_thread::sleep_for(1ms);
    }
  });
  const auto first = manager.receive(500ms);
  REQUIRE(first.has_value());
  CHECK(contains(*first, "READY=1"));
  int feeds = 0;
  for (const auto until = Clock::now() + 500ms; Clock::now() < until;)
    if (const auto m = manager.receive(100ms); m && contains(*m, "WATCHDOG=1")) ++feeds;
  CHECK(feeds >= 5);  // every 50 ms while the loop advances; at least half of them on a loaded machine

  advancing = false;                  // stuck: the loop's tick stands still
  std::this_thread::sleep_for(60ms);  // a feed for the last moves may still be on its way
  while (manager.receive(0ms)) {
  }
  std::optional<std::string> during_stall;
  for (const auto until = Clock::now() + 600ms; Clock::now() < until && !during_stall;)
    during_stall = manager.receive(100ms);
  CHECK_FALSE(during_stall.has_value());

  advancing = true;
  const auto resumed = manager.receive(500ms);
  REQUIRE(resumed.has_value());
  CHECK(contains(*resumed, "WATCHDOG=1"));
  done = true;
  loop.join();
  watchdog.stop();
  std::optional<std::string> last;
  while (const auto m = manager.receive(100ms)) last = m;
  REQUIRE(last.has_value());
  CHECK(contains(*last, "STOPPING=1"));
}

TEST_CASE("loop watchdog: without a service watchdog nothing is fed, and a device that is none is refused",
          "[board][watchdog]") {
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("NOTIFY_SOCKET");
  auto opened = LoopWatchdog::open({});
  REQUIRE(opened.ok());
  CHECK(opened.value().service_interval() == 0us);
  CHECK(opened.value().description().find("no service watchdog") != std::string::npos);
  auto not_a_watchdog = LoopWatchdog::open({"/dev/null", std::chrono::seconds(2)});
  REQUIRE_FALSE(not_a_watchdog.ok());
  CHECK(not_a_watchdog.error().message.find("/dev/null") != std::string::npos);
  auto missing = LoopWatchdog::open({"/dev/no-such-watchdog", std::chrono::seconds(2)});
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message.find("cannot open") != std::string::npos);
}

namespace {

enum class Hang { stuck_in_step, stopped_process };

struct KillTimes {
  double stuck_to_kill_ms = 0;     // from the loop's last step to the manager's SIGABRT
  double stuck_to_exit_ms = 0;     // to the process gone, its motor stopped
  double last_feed_after_ms = -1;  // the last WATCHDOG=1 sent after the loop's last step (negative: before)
  int feeds_after_stuck = 0;       // WATCHDOG=1 sent after the loop's last step
  bool motor_off = false;
};

std::int64_t realtime_ns() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

// When the loop took its last step, in both clocks: the monotonic one for the kill's timing, the realtime one to
// compare with the kernel's stamps on the feeds.
struct Stuck {
  std::int64_t monotonic_ns = 0;
  std::int64_t realtime_ns = 0;
};

// A lever-fw in miniature in a child: a real PWM motor on a sysfs tree of its own, driven at half torque by a real
// RealtimeLoop that feeds a LoopWatchdog, with lever-fw's motor-stop signal handlers; after 300 ticks it hangs.
// The parent is the service manager.
KillTimes run_and_hang(Hang hang) {
  lever::test::PwmSysfsTree tree(0, 0);
  NotifyListener manager;
  int stuck_pipe[2];
  REQUIRE(::pipe(stuck_pipe) == 0);
  std::fflush(nullptr);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::alarm(20);
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);  // SIGABRT's default action writes no core into the test's directory
    manager.export_for(::getpid());
    lever::board::PwmMotorConfig motor_config;
    motor_config.sysfs_root = tree.root();
    motor_config.torque_constant_nm_per_a = 0.05;
    motor_config.full_scale_current_a = 20.0;
    motor_config.positive_torque_only = true;
    auto motor = lever::board::PwmMotor::open(motor_config);
    if (!motor || !lever::board::install_motor_stop_signal_handlers()) ::_exit(3);
    auto watchdog = LoopWatchdog::open({});
    if (!watchdog) ::_exit(4);
    lever::board::RealtimeConfig loop_config;
    loop_config.fifo_priority = 0;
    loop_config.lock_memory = false;
    loop_config.prefault_stack_bytes = 64 * 1024;
    auto loop = RealtimeLoop::open(loop_config);
    if (!loop) ::_exit(5);
    std::stop_source stop;
    bool hung = false;
    loop.value().run(
        [&](lever::fw::Tick tick) {
          motor.value().command({0.5, true});
          watchdog.value().advanced(tick);
          // >=, not ==: a wake-up late by a period or more skips ticks (period_tracker.hpp), and on a loaded
          // machine tick 300 itself may never be served
          if (tick >= 300 && !hung) {
            hung = true;
            const Stuck now{lever::board::monotonic_ns(), realtime_ns()};
            if (::write(stuck_pipe[1], &now, sizeof now) != sizeof now) ::_exit(6);
            if (hang == Hang::stuck_in_step)
              for (;;) ::pause();  // a step that never ends: a hung write, a lock never released
          }
        },
        stop.get_token());
    ::_exit(7);
  }
  ::close(stuck_pipe[1]);
  KillTimes times;
  Stuck stuck;
  std::int64_t& stuck_ns = stuck.monotonic_ns;
  std::optional<std::int64_t> last_feed_ns, kill_ns;
  std::vector<std::int64_t> feeds_sent_ns;
  // The manager: feeds are awaited at most WatchdogSec apart (from READY=1 on); a stopped process is one
  // way of hanging, done here once the loop has stepped 300 times.
  pollfd p{stuck_pipe[0], POLLIN, 0};
  bool ready = false;
  auto deadline = Clock::now() + 10s;
  while (!kill_ns && Clock::now() < deadline) {
    if (const auto m = manager.receive_stamped(1ms)) {
      if (contains(m->text, "READY=1")) ready = true;
      if (contains(m->text, "WATCHDOG=1")) {
        last_feed_ns = lever::board::monotonic_ns();
        feeds_sent_ns.push_back(m->sent_realtime_ns);
      }
    }
    if (stuck_ns == 0 && ::poll(&p, 1, 0) > 0) {
      if (::read(stuck_pipe[0], &stuck, sizeof stuck) != sizeof stuck) {
        int status = 0;
        ::waitpid(child, &status, 0);
        FAIL("the child ended before its loop hung, exit code " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1));
      }
      if (hang == Hang::stopped_process) ::kill(child, SIGSTOP);
    }
    const std::int64_t now = lever::board::monotonic_ns();
    // Judged from the hang on: a child starved of the CPU before its 300th tick is not the case measured.
    if (stuck_ns != 0 && ready && last_feed_ns &&
        now - *last_feed_ns > std::chrono::nanoseconds(kWatchdogSec).count()) {
      ::kill(child, SIGABRT);  // WatchdogSignal=SIGABRT
      ::kill(child, SIGCONT);  // as systemd does after it, so a stopped process handles it
      kill_ns = now;
    }
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  const std::int64_t exit_ns = lever::board::monotonic_ns();
  ::close(stuck_pipe[0]);
  REQUIRE(stuck_ns != 0);
  REQUIRE(kill_ns.has_value());
  CHECK(WIFSIGNALED(status));
  if (WIFSIGNALED(status)) CHECK(WTERMSIG(status) == SIGABRT);
  times.stuck_to_kill_ms = static_cast<double>(*kill_ns - stuck_ns) * 1e-6;
  times.stuck_to_exit_ms = static_cast<double>(exit_ns - stuck_ns) * 1e-6;
  times.last_feed_after_ms = static_cast<double>(feeds_sent_ns.back() - stuck.realtime_ns) * 1e-6;
  for (const std::int64_t sent : feeds_sent_ns) times.feeds_after_stuck += sent > stuck.realtime_ns ? 1 : 0;
  times.motor_off = tree.read("enable") == "1" && tree.read("duty_cycle") == "0";  // the inactive state
  return times;
}

}  // namespace

TEST_CASE("loop watchdog: a loop stuck in a step, or a stopped process, is fed at most once more and its motor stopped",
          "[board][watchdog]") {
  const auto hang = GENERATE(Hang::stuck_in_step, Hang::stopped_process);
  CAPTURE(hang == Hang::stuck_in_step ? "stuck in a step" : "stopped process");
  const KillTimes t = run_and_hang(hang);
  std::printf(
      "measured: loop watchdog, %s: %d feed(s) sent after the loop's last step, the last %.1f ms after it, killed "
      "after %.1f ms, "
      "gone with its motor off after %.1f ms (the service manager's bound %lld ms)\n",
      hang == Hang::stuck_in_step ? "stuck in a step" : "stopped process", t.feeds_after_stuck, t.last_feed_after_ms,
      t.stuck_to_kill_ms, t.stuck_to_exit_ms, static_cast<long long>((kWatchdogSec + 50ms).count()));
  CHECK(t.motor_off);
  // The feeder fed nothing the loop did not do: after the loop's last step at most one feed, the check that saw
  // that step, so the service manager kills within WatchdogSec + one check. Counted, not timed: when this busy
  // machine schedules the feeder is not the feeder's logic. The bound in time is measured in virtual time on the
  // board image, from the PWM controller's stamps (tests/image/safety_units.sh).
  CHECK(t.feeds_after_stuck <= 1);
}

// Not run by ctest: it needs a watchdog device, and a mistake resets the machine. Run in the kernel rig's guest
// with softdog loaded (docs/deploy.md, "The units"): LEVER_WATCHDOG_DEVICE=/dev/watchdog. A loop that advances
// keeps the board up past the device's timeout; the deliberate stop's magic close disarms it. Set
// LEVER_WATCHDOG_HANG=1 to see the other side: the loop stops advancing, and softdog resets the guest.
TEST_CASE("loop watchdog: a hardware watchdog fed while the loop advances, disarmed by a clean stop",
          "[.softdog][watchdog]") {
  const char* device = std::getenv("LEVER_WATCHDOG_DEVICE");
  REQUIRE(device != nullptr);
  ::unsetenv("WATCHDOG_USEC");
  auto opened = LoopWatchdog::open({device, std::chrono::seconds(1)});
  REQUIRE(opened.ok());
  LoopWatchdog& watchdog = opened.value();
  std::printf("%s\n", watchdog.description().c_str());
  CHECK(watchdog.check_interval() == 250ms);
  const bool hang = std::getenv("LEVER_WATCHDOG_HANG") != nullptr;
  std::uint64_t tick = 0;
  for (const auto until = Clock::now() + 3s; Clock::now() < until;) {
    watchdog.advanced(++tick);
    std::this_thread::sleep_for(1ms);
  }
  CHECK(watchdog.feeds() >= 8);  // 3 s at one feed per 250 ms check, on a slow guest fewer
  std::printf("fed %llu times in 3 s of an advancing loop; the guest is up past the 1 s timeout\n",
              static_cast<unsigned long long>(watchdog.feeds()));
  std::fflush(stdout);
  if (hang) {
    std::printf("the loop stops advancing now: softdog should reset the guest within 1 s\n");
    std::fflush(stdout);
    std::this_thread::sleep_for(5s);
    FAIL("still running 5 s after the loop stopped advancing");
  }
  watchdog.stop();
  std::this_thread::sleep_for(2s);  // past the timeout: a watchdog left armed would have reset the guest by now
  std::printf("stopped cleanly; the guest is up 2 s after the magic close\n");
}
