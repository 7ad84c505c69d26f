#include "lever/board/gpio_encoder.hpp"

#include <gpiod.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <optional>
#include <utility>

#include "gpio_chip.hpp"
#include "lever/board/config_error.hpp"
#include "lever/board/monotonic_clock.hpp"

namespace lever::board {

namespace {

std::uint64_t to_ns(const timespec& ts) noexcept {
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000u + static_cast<std::uint64_t>(ts.tv_nsec);
}

// errno is taken before the message is built: building it may allocate, which may set errno.
Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

// The level reader must not run at the real-time priority it would inherit (lever-fw runs as SCHED_FIFO 50
// under systemd): it waits on the GPIO driver's lock, and it has nothing to do that is urgent. Nice 0 unless the
// process was made nicer than that.
void become_ordinary_thread() noexcept {
  sched_param param{};
  param.sched_priority = 0;
  ::pthread_setschedparam(::pthread_self(), SCHED_OTHER, &param);
  const auto tid = static_cast<id_t>(::gettid());
  errno = 0;
  const int nice = ::getpriority(PRIO_PROCESS, tid);
  if (errno == 0 && nice < 0) ::setpriority(PRIO_PROCESS, tid, 0);
}

}  // namespace

// The level checks' value reads run on a thread of their own. A value read enters the GPIO driver, which on
// gpio-sim and on any expander behind I2C or SPI takes the chip's mutex; whoever writes the lines may hold it,
// and a plain mutex lends the loop's priority to nobody, so the loop would wait as long as that writer is kept
// from running. The event reads stay on the loop: the kernel's event FIFOs are under a spinlock.
//
// The loop asks by a request number and a write to an eventfd; the reader answers the newest request with the
// values and the time around their read, then publishes the request's number. The loop reads the answer only
// once the number is its own, and the reader writes an answer only for a request newer than its last, which
// the loop makes only after it is done with the last answer: the two never touch `answer` at once.
struct LevelAnswer {
  std::uint64_t lo_ns = 0, hi_ns = 0;
  fw::AbState values = 0;
  bool ok = false;
};

struct GpioEncoder::Impl {
  ChipPtr chip;
  std::array<gpiod_line*, kEncoderLines> lines{};  // owned by the chip; nullptr: no index line
  std::array<int, kEncoderLines> fds{-1, -1, -1};
  EdgeTracker tracker;
  std::string description;

  int wake_fd = -1;  // eventfd, non-blocking: a request, or the stop
  pthread_t reader{};
  bool reader_started = false;
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> requested{0};  // the loop's newest request
  std::atomic<std::uint64_t> answered{0};   // the request `answer` is for
  LevelAnswer answer;
  // The loop's own: the request it waits for (0: none), and the tracker's A/B events when it asked.
  std::uint64_t next_request = 0;
  std::uint64_t waiting_for = 0;
  std::uint64_t ab_events_asked = 0;

  Impl(ChipPtr c, std::array<gpiod_line*, kEncoderLines> l, std::array<int, kEncoderLines> f, EdgeTracker t,
       std::string d)
      : chip(std::move(c)), lines(l), fds(f), tracker(t), description(std::move(d)) {}
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  // The reader goes before the lines it reads are released with the chip.
  ~Impl();

  // 0, or the errno of what failed.
  int start_level_reader() noexcept;
  void run_level_reader() noexcept;

  // Reads every line's FIFO; returns the time after which each was found empty (or its stage full).
  std::uint64_t read_events() noexcept;
  void take_level_answer() noexcept;
  void ask_for_levels() noexcept;
};

GpioEncoder::Impl::~Impl() {
  if (reader_started) {
    stop.store(true, std::memory_order_release);
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto written = ::write(wake_fd, &one, sizeof one);
    ::pthread_join(reader, nullptr);
  }
  if (wake_fd >= 0) ::close(wake_fd);
}

int GpioEncoder::Impl::start_level_reader() noexcept {
  wake_fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd < 0) return errno;
  // A small stack: RealtimeLoop's mlockall locks every mapped page, a thread's whole stack too, and glibc's default
  // is RLIMIT_STACK (8 MiB) where this thread needs a few KiB for a poll and two ioctls.
  const std::size_t stack =
      std::max<std::size_t>(128 * 1024, static_cast<std::size_t>(::sysconf(_SC_THREAD_STACK_MIN)));
  pthread_attr_t attr;
  if (const int err = ::pthread_attr_init(&attr); err != 0) return err;
  int err = ::pthread_attr_setstacksize(&attr, stack);
  if (err == 0) {
    err = ::pthread_create(
        &reader, &attr,
        [](void* self) -> void* {
          static_cast<Impl*>(self)->run_level_reader();
          return nullptr;
        },
        this);
  }
  ::pthread_attr_destroy(&attr);
  reader_started = err == 0;
  return err;
}

void GpioEncoder::Impl::run_level_reader() noexcept {
  become_ordinary_thread();
  ::pthread_setname_np(::pthread_self(), "lever-enc-lvl");  // at most 15 characters
  std::uint64_t last = 0;
  for (;;) {
    pollfd wake{wake_fd, POLLIN, 0};
    if (::poll(&wake, 1, -1) < 0) continue;  // EINTR; an eventfd has no other way to fail here
    std::uint64_t count = 0;
    [[maybe_unused]] const auto got = ::read(wake_fd, &count, sizeof count);
    if (stop.load(std::memory_order_acquire)) return;
    // Requests that came while the last was read are answered by one read: the loop waits for the newest only.
    const std::uint64_t request = requested.load(std::memory_order_acquire);
    if (request == last) continue;
    last = request;
    answer.lo_ns = static_cast<std::uint64_t>(monotonic_ns());
    const int a = gpiod_line_get_value(lines[0]);
    const int b = gpiod_line_get_value(lines[1]);
    answer.hi_ns = static_cast<std::uint64_t>(monotonic_ns());
    answer.ok = a >= 0 && b >= 0;
    answer.values = fw::ab(a > 0, b > 0);
    answered.store(request, std::memory_order_release);
  }
}

std::uint64_t GpioEncoder::Impl::read_events() noexcept {
  std::array<gpiod_line_event, kKernelEventFifo> buffer{};
  std::uint64_t complete = UINT64_MAX;
  for (std::size_t i = 0; i < kEncoderLines; ++i) {
    if (fds[i] < 0) continue;
    const auto line = static_cast<EncoderLine>(i);
    for (;;) {
      // Always ask for a whole FIFO: only then does a full answer prove the FIFO was full. With less room the
      // events wait in the kernel (and a FIFO that fills meanwhile still shows as full on a later read).
      if (tracker.room(line) < kKernelEventFifo) {
        complete = std::min(complete, tracker.newest_staged_ns(line));
        break;
      }
      const std::uint64_t before = static_cast<std::uint64_t>(monotonic_ns());
      const int n = gpiod_line_event_read_fd_multiple(fds[i], buffer.data(), kKernelEventFifo);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK) tracker.note_read_error();
        complete = std::min(complete, before);
        break;
      }
      for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
        tracker.stage(line, LineEvent{to_ns(buffer[k].ts), buffer[k].event_type == GPIOD_LINE_EVENT_RISING_EDGE});
      }
      if (static_cast<unsigned>(n) < kKernelEventFifo) {
        // The read stops only when the FIFO is empty or our buffer full: all that was queued before it is here.
        complete = std::min(complete, before);
        break;
      }
      tracker.note_fifo_full();
    }
  }
  return complete;
}

void GpioEncoder::Impl::take_level_answer() noexcept {
  if (waiting_for == 0) return;
  if (tracker.ab_events() != ab_events_asked || !tracker.wants_level_check()) {
    // The lines moved since we asked: the answer is no longer a read of the levels the tracker holds. A new
    // request follows once the tracker is idle again; the reader answers it after the one it may be doing.
    waiting_for = 0;
    return;
  }
  // Not yet: the reader may be waiting for the driver, which is what it is there for.
  if (answered.load(std::memory_order_acquire) != waiting_for) return;
  waiting_for = 0;
  if (!answer.ok) {
    tracker.note_read_error();
    return;
  }
  // Nothing moved since the request and the values were read after it: as good as a read made right then.
  tracker.begin_level_check(answer.values, answer.lo_ns, answer.hi_ns);
}

void GpioEncoder::Impl::ask_for_levels() noexcept {
  const std::uint64_t request = ++next_request;
  requested.store(request, std::memory_order_release);
  const std::uint64_t one = 1;
  // Never waits: the eventfd is non-blocking, and its counter would have to near 2^64 to refuse.
  if (::write(wake_fd, &one, sizeof one) != static_cast<ssize_t>(sizeof one)) {
    tracker.note_read_error();  // no check this time; asked again on the next drain
    return;
  }
  waiting_for = request;
  ab_events_asked = tracker.ab_events();
}

GpioEncoder::GpioEncoder(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
GpioEncoder::GpioEncoder(GpioEncoder&&) noexcept = default;
GpioEncoder& GpioEncoder::operator=(GpioEncoder&&) noexcept = default;
GpioEncoder::~GpioEncoder() = default;

Result<GpioEncoder> GpioEncoder::open(const GpioEncoderConfig& config) {
  if (const auto problems = config.validate(); !problems.empty()) return config_error("encoder config", problems);
  ChipPtr chip = open_gpio_chip(config.chip);
  if (!chip) {
    const int err = errno;
    return os_error(err, "encoder chip \"" + config.chip + "\": cannot open (no such path, name or label?)");
  }
  const std::string chip_text = describe_chip(chip.get());

  struct Wanted {
    const char* field;
    const LineRef* ref;
    int request_type;
  };
  const std::array<Wanted, kEncoderLines> wanted{{
      {"line_a", &config.line_a, GPIOD_LINE_REQUEST_EVENT_BOTH_EDGES},
      {"line_b", &config.line_b, GPIOD_LINE_REQUEST_EVENT_BOTH_EDGES},
      {"line_z", config.line_z ? &*config.line_z : nullptr, GPIOD_LINE_REQUEST_EVENT_RISING_EDGE},
  }};
  std::array<gpiod_line*, kEncoderLines> lines{};
  std::array<int, kEncoderLines> fds{-1, -1, -1};
  std::string description = chip_text;
  const int flags = config.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  for (std::size_t i = 0; i < kEncoderLines; ++i) {
    const Wanted& w = wanted[i];
    if (w.ref == nullptr) continue;
    const std::string where = std::string("encoder ") + w.field + " (" + w.ref->describe() + " on " + chip_text + ")";
    gpiod_line* line = find_gpio_line(chip.get(), *w.ref);
    if (line == nullptr) {
      const int err = errno;
      return os_error(err, where + ": " + missing_line_reason(chip.get(), *w.ref));
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (lines[j] == line) return os_error(EINVAL, where + ": the same line as " + wanted[j].field);
    }
    const gpiod_line_request_config request{config.consumer.c_str(), w.request_type, flags};
    if (gpiod_line_request(line, &request, 0) < 0) {
      const int err = errno;
      return os_error(err, where + ": cannot request its edge events" + line_user_if_busy(line, err));
    }
    lines[i] = line;
    fds[i] = nonblocking_event_fd(line);
    if (fds[i] < 0) {
      const int err = errno;
      return os_error(err, where + ": cannot make its events non-blocking");
    }
    description += std::string(" ") + "ABZ"[i] + "=" + std::to_string(gpiod_line_offset(line));
  }

  // After the requests, so that every edge after this read is also an event; edges between the requests and
  // the read are in both, which the tracker's settle window absorbs.
  const int a = gpiod_line_get_value(lines[0]);
  const int err_a = errno;
  const int b = gpiod_line_get_value(lines[1]);
  const int err_b = errno;
  const std::uint64_t read_end = static_cast<std::uint64_t>(monotonic_ns());
  if (a < 0) return os_error(err_a, "encoder line_a: cannot read its level");
  if (b < 0) return os_error(err_b, "encoder line_b: cannot read its level");
  const std::uint64_t margin_ns = std::uint64_t{config.edge_latency_us} * 1000u;
  EdgeTracker tracker(fw::ab(a != 0, b != 0), read_end, margin_ns);
  auto impl = std::make_unique<Impl>(std::move(chip), lines, fds, tracker, std::move(description));
  if (const int err = impl->start_level_reader(); err != 0) {
    return os_error(err, "encoder on " + chip_text + ": cannot start the thread that reads its levels");
  }
  return GpioEncoder(std::move(impl));
}

fw::EdgeDrain GpioEncoder::drain_edges(fw::EncoderEdge* out, std::size_t capacity) noexcept {
  if (!impl_) return {};
  // Before this drain's edges: an answer that came in the sleep since the last drain begins its check with
  // the levels it was asked for, whatever the lines do now.
  impl_->take_level_answer();
  const std::uint64_t read_empty_at = impl_->read_events();
  const fw::EdgeDrain drain = impl_->tracker.deliver(out, capacity, read_empty_at);
  if (impl_->waiting_for == 0 && impl_->tracker.wants_level_check()) impl_->ask_for_levels();
  return drain;
}

fw::AbState GpioEncoder::levels() const noexcept { return impl_ ? impl_->tracker.levels() : fw::AbState{0}; }

const EdgeStats& GpioEncoder::stats() const noexcept {
  static const EdgeStats none{};
  return impl_ ? impl_->tracker.stats() : none;
}

const std::string& GpioEncoder::description() const noexcept {
  static const std::string closed = "(moved from)";
  return impl_ ? impl_->description : closed;
}

}  // namespace lever::board
