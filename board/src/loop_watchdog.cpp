#include "lever/board/loop_watchdog.hpp"

#include <fcntl.h>
#include <linux/watchdog.h>
#include <sys/ioctl.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <system_error>

#include "lever/board/unique_fd.hpp"

namespace lever::board {
namespace {

using std::chrono::microseconds;

Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

std::string milliseconds_text(microseconds us) { return std::to_string(us.count() / 1000) + " ms"; }

}  // namespace

struct LoopWatchdog::Shared {
  std::atomic<std::uint64_t> tick{0};
  std::atomic<std::uint64_t> feeds{0};
  microseconds service{0};
  microseconds check{100'000};
  UniqueFd device;
  std::string device_name;
  std::chrono::seconds device_timeout{0};
  std::mutex mutex;
  std::condition_variable_any wake;

  void run(const std::stop_token& stop) {
    std::uint64_t seen = 0;
    bool ready = false;
    std::unique_lock lock(mutex);
    while (!wake.wait_for(lock, stop, check, [] { return false; }) && !stop.stop_requested()) {
      const std::uint64_t now = tick.load(std::memory_order_relaxed);
      if (now == seen) continue;  // the loop did not move: feed nothing
      seen = now;
      if (!ready) {
        ::sd_notify(0, "READY=1\nSTATUS=control loop running");
        ready = true;
      }
      if (service.count() > 0) ::sd_notify(0, "WATCHDOG=1");
      if (device) ::ioctl(device.get(), WDIOC_KEEPALIVE, 0);
      feeds.fetch_add(1, std::memory_order_relaxed);
    }
  }
};

Result<LoopWatchdog> LoopWatchdog::open(const LoopWatchdogConfig& config) {
  auto shared = std::make_unique<Shared>();
  std::uint64_t usec = 0;
  if (::sd_watchdog_enabled(0, &usec) > 0) shared->service = microseconds(usec);
  if (!config.device.empty()) {
    if (config.device_timeout < std::chrono::seconds(1) || config.device_timeout > std::chrono::seconds(60))
      return Error{"watchdog " + config.device + ": a timeout of 1 to 60 s", EINVAL};
    shared->device = UniqueFd(::open(config.device.c_str(), O_WRONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
    if (!shared->device) {
      const int err = errno;
      return os_error(err, "watchdog " + config.device + ": cannot open");
    }
    int timeout = static_cast<int>(config.device_timeout.count());
    if (::ioctl(shared->device.get(), WDIOC_SETTIMEOUT, &timeout) != 0) {
      const int err = errno;
      return os_error(err, "watchdog " + config.device + ": cannot set its timeout to " +
                               std::to_string(config.device_timeout.count()) + " s (not a watchdog device?)");
    }
    shared->device_name = config.device;
    shared->device_timeout = std::chrono::seconds(timeout);  // what the driver made of it
  }
  microseconds shortest = shared->service;
  if (shared->device && (shortest.count() == 0 || shared->device_timeout < shortest)) shortest = shared->device_timeout;
  if (shortest.count() > 0) shared->check = std::max(shortest / 4, microseconds(1000));
  try {
    return LoopWatchdog(std::move(shared));
  } catch (const std::system_error& failure) {
    return Error{std::string("watchdog: cannot start its thread: ") + failure.what(), failure.code().value()};
  }
}

LoopWatchdog::LoopWatchdog(std::unique_ptr<Shared> shared)
    : shared_(std::move(shared)), thread_([state = shared_.get()](std::stop_token stop) { state->run(stop); }) {}

LoopWatchdog::LoopWatchdog(LoopWatchdog&&) noexcept = default;

LoopWatchdog& LoopWatchdog::operator=(LoopWatchdog&& other) noexcept {
  if (this != &other) {
    stop();
    thread_ = std::move(other.thread_);
    shared_ = std::move(other.shared_);
  }
  return *this;
}

LoopWatchdog::~LoopWatchdog() { stop(); }

void LoopWatchdog::advanced(std::uint64_t tick) noexcept { shared_->tick.store(tick, std::memory_order_relaxed); }

void LoopWatchdog::stop() noexcept {
  if (!thread_.joinable()) return;
  thread_.request_stop();
  thread_.join();
  ::sd_notify(0, "STOPPING=1");
  if (shared_->device) {
    // The magic close: a driver without nowayout stops counting, so a deliberate stop resets no board.
    const char magic = 'V';
    if (::write(shared_->device.get(), &magic, 1) != 1) {
      // Nothing to do about it here; the driver's own timeout stands.
    }
    shared_->device = UniqueFd();
  }
}

std::chrono::microseconds LoopWatchdog::service_interval() const noexcept { return shared_->service; }
std::chrono::microseconds LoopWatchdog::check_interval() const noexcept { return shared_->check; }
std::chrono::microseconds LoopWatchdog::kill_bound() const noexcept { return shared_->service + shared_->check; }
std::uint64_t LoopWatchdog::feeds() const noexcept { return shared_->feeds.load(std::memory_order_relaxed); }

std::string LoopWatchdog::description() const {
  std::string d = shared_->service.count() > 0
                      ? "service watchdog " + milliseconds_text(shared_->service) + ", checked every " +
                            milliseconds_text(shared_->check) + " (a stuck loop is killed within " +
                            milliseconds_text(kill_bound()) + ")"
                      : "no service watchdog (WATCHDOG_USEC not set)";
  if (shared_->device) d += "; " + shared_->device_name + " " + std::to_string(shared_->device_timeout.count()) + " s";
  return d;
}

}  // namespace lever::board
