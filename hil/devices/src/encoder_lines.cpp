#include "lever/hil/devices/encoder_lines.hpp"

#include <time.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <thread>

#include "lever/board/config_error.hpp"
#include "lever/board/monotonic_clock.hpp"
#include "lever/fw/hal.hpp"
#include "sim_line.hpp"

namespace lever::hil::devices {

namespace {

using board::Error;

// The A/B levels (as the reader sees them: fw::ab) in forward order; one line changes between neighbours.
constexpr fw::AbState kGray[4] = {fw::ab(false, false), fw::ab(false, true), fw::ab(true, true), fw::ab(true, false)};

int floor_mod4(std::int64_t value) noexcept { return static_cast<int>(((value % 4) + 4) % 4); }

std::uint64_t now_ns() noexcept { return static_cast<std::uint64_t>(board::monotonic_ns()); }

void sleep_until(std::uint64_t deadline_ns) noexcept {
  const timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000u), static_cast<long>(deadline_ns % 1'000'000'000u)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

struct EncoderLines::Impl {
  Impl(SimLine line_a, SimLine line_b) : a(std::move(line_a)), b(std::move(line_b)) {}

  SimLine a;
  SimLine b;
  std::optional<SimLine> z;
  bool active_low = false;
  std::optional<std::int64_t> index_at;
  std::uint64_t period_ns = 0;
  int phase_at_zero = 0;  // where in kGray the lines were at open()
  std::string description;

  std::atomic<std::int64_t> target{0};
  std::atomic<std::int64_t> count{0};
  // Bumped by set_count() and the destructor; the idle thread waits for it to change (a futex, no lock).
  std::atomic<std::uint32_t> wake{0};
  std::atomic<bool> stopping{false};
  std::atomic<std::uint64_t> edges{0};
  std::atomic<std::uint64_t> max_backlog{0};
  std::atomic<std::uint64_t> index_pulses{0};
  std::atomic<std::uint64_t> write_errors{0};
  std::atomic<std::int64_t> last_edge_ns{0};

  // The thread's own.
  bool z_asserted = false;
  std::uint64_t next_edge_ns = 0;
  std::thread thread;

  ~Impl() {
    if (!thread.joinable()) return;
    stopping.store(true);
    wake.fetch_add(1);
    wake.notify_all();
    thread.join();
  }

  bool drive(SimLine& line, bool asserted) noexcept { return line.drive(asserted != active_low); }

  bool drive_z(bool asserted) noexcept {
    if (!drive(*z, asserted)) return false;
    z_asserted = asserted;
    if (asserted) index_pulses.fetch_add(1, std::memory_order_relaxed);
    return true;
  }

  // At most the rate: deadlines on a grid, but one that starts again from now after a wait (idle, or a thread
  // held up), so the lines never burst to catch up faster than the rate.
  void pace() noexcept {
    next_edge_ns += period_ns;
    if (const std::uint64_t now = now_ns(); next_edge_ns < now) {
      next_edge_ns = now;
      return;
    }
    sleep_until(next_edge_ns);
  }

  void step(std::int64_t from, int direction) noexcept {
    const fw::AbState before = kGray[floor_mod4(phase_at_zero + from)];
    const fw::AbState after = kGray[floor_mod4(phase_at_zero + from + direction)];
    const bool a_moves = ((before ^ after) & fw::ab(true, false)) != 0;
    const bool level = (after & (a_moves ? fw::ab(true, false) : fw::ab(false, true))) != 0;
    if (!drive(a_moves ? a : b, level)) {
      write_errors.fetch_add(1, std::memory_order_relaxed);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      return;
    }
    const std::int64_t now_at = from + direction;
    last_edge_ns.store(static_cast<std::int64_t>(now_ns()), std::memory_order_relaxed);
    count.store(now_at, std::memory_order_release);
    edges.fetch_add(1, std::memory_order_relaxed);
    // After the A/B edge, so the reader (which merges its lines by kernel time) finds Z at this count.
    const bool want_z = index_at && now_at == *index_at;
    if (z && want_z != z_asserted && !drive_z(want_z)) write_errors.fetch_add(1, std::memory_order_relaxed);
  }

  void run() noexcept {
    while (!stopping.load()) {
      const std::uint32_t seen = wake.load(std::memory_order_acquire);
      const std::int64_t goal = target.load(std::memory_order_acquire);
      const std::int64_t at = count.load(std::memory_order_relaxed);
      if (goal == at) {
        wake.wait(seen, std::memory_order_acquire);
        continue;
      }
      pace();
      if (stopping.load()) return;
      step(at, goal > at ? 1 : -1);
    }
  }
};

namespace {

// Apart from open(): GCC 12 sees a free of a non-heap object in the inlined destructor of a moved-from
// Result<SimLine> there (a false -Wfree-nonheap-object).
[[gnu::noinline]] std::optional<Error> open_z(std::optional<SimLine>& into, const board::GpioEncoderConfig& config) {
  auto z = SimLine::open(config.chip, *config.line_z, "encoder lines: line_z");
  if (!z) return z.error();
  into.emplace(std::move(z).value());
  return std::nullopt;
}

}  // namespace

board::Result<EncoderLines> EncoderLines::open(const board::GpioEncoderConfig& config, EncoderLinesOptions options) {
  if (const auto problems = config.validate(); !problems.empty()) return board::config_error("encoder lines", problems);
  if (!(options.max_edge_rate_hz > 0) || !std::isfinite(options.max_edge_rate_hz)) {
    return Error{
        "encoder lines: max_edge_rate_hz: " + std::to_string(options.max_edge_rate_hz) + ", must be above 0 and finite",
        EINVAL};
  }
  auto a = SimLine::open(config.chip, config.line_a, "encoder lines: line_a");
  if (!a) return a.error();
  auto b = SimLine::open(config.chip, config.line_b, "encoder lines: line_b");
  if (!b) return b.error();
  auto impl = std::make_unique<Impl>(std::move(a).value(), std::move(b).value());
  if (config.line_z) {
    if (auto problem = open_z(impl->z, config)) return *problem;
  }
  impl->active_low = config.active_low;
  impl->index_at = options.index_at_count;
  impl->period_ns = static_cast<std::uint64_t>(std::llround(1e9 / options.max_edge_rate_hz));

  const auto level_a = impl->a.level();
  const auto level_b = impl->b.level();
  if (!level_a || !level_b) {
    const int err = errno;
    return Error{"encoder lines: cannot read the level of " + (level_a ? impl->b.description() : impl->a.description()),
                 err};
  }
  // Pulls at the current levels: a line no one has requested shows its pull, and must not move when it is.
  const bool logical_a = *level_a != config.active_low;
  const bool logical_b = *level_b != config.active_low;
  if (!impl->drive(impl->a, logical_a) || !impl->drive(impl->b, logical_b)) {
    const int err = errno;
    return Error{"encoder lines: cannot set the pulls on " + impl->a.chip_description(), err};
  }
  const fw::AbState start = fw::ab(logical_a, logical_b);
  while (kGray[impl->phase_at_zero] != start) ++impl->phase_at_zero;
  if (impl->z && !impl->drive_z(impl->index_at == 0)) {
    const int err = errno;
    return Error{"encoder lines: cannot set the pull on " + impl->z->description(), err};
  }

  impl->description = impl->a.chip_description() + " A=" + std::to_string(impl->a.offset()) +
                      " B=" + std::to_string(impl->b.offset()) +
                      (impl->z ? " Z=" + std::to_string(impl->z->offset()) : std::string()) + ", " +
                      std::to_string(std::llround(options.max_edge_rate_hz)) + " edges/s" +
                      (impl->index_at ? ", index at " + std::to_string(*impl->index_at) : std::string());
  Impl* self = impl.get();
  self->thread = std::thread([self] { self->run(); });
  return EncoderLines(std::move(impl));
}

EncoderLines::EncoderLines(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
EncoderLines::EncoderLines(EncoderLines&&) noexcept = default;
EncoderLines& EncoderLines::operator=(EncoderLines&&) noexcept = default;
EncoderLines::~EncoderLines() = default;

void EncoderLines::set_count(std::int64_t target) noexcept {
  Impl& s = *impl_;
  const std::int64_t previous = s.target.exchange(target, std::memory_order_acq_rel);
  const std::int64_t behind = target - s.count.load(std::memory_order_relaxed);
  const auto backlog = static_cast<std::uint64_t>(behind < 0 ? -behind : behind);
  std::uint64_t seen = s.max_backlog.load(std::memory_order_relaxed);
  while (backlog > seen && !s.max_backlog.compare_exchange_weak(seen, backlog, std::memory_order_relaxed)) {
  }
  // The world sets the count every millisecond and it mostly stays put: the thread is then idle at it or on
  // its way there, and a wake-up per call would cost a futex call and a context switch each time for nothing.
  if (previous == target) return;
  s.wake.fetch_add(1, std::memory_order_release);
  s.wake.notify_one();
}

EncoderLinesStats EncoderLines::stats() const noexcept {
  const Impl& s = *impl_;
  return {s.edges.load(std::memory_order_relaxed),        s.count.load(std::memory_order_acquire),
          s.max_backlog.load(std::memory_order_relaxed),  s.index_pulses.load(std::memory_order_relaxed),
          s.write_errors.load(std::memory_order_relaxed), s.last_edge_ns.load(std::memory_order_relaxed)};
}

const std::string& EncoderLines::description() const noexcept { return impl_->description; }

}  // namespace lever::hil::devices
