#include "lever/board/gpio_encoder.hpp"

#include <fcntl.h>
#include <gpiod.h>

#include <algorithm>
#include <array>
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

// The v1 interface's per-line event FIFO (gpiolib-cdev.c: DECLARE_KFIFO(events, struct gpioevent_data, 16)).
// A read asking for this many that gets them all has found the FIFO full.
constexpr unsigned kKernelFifo = 16;

std::uint64_t to_ns(const timespec& ts) noexcept {
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000u + static_cast<std::uint64_t>(ts.tv_nsec);
}

// errno is taken before the message is built: building it may allocate, which may set errno.
Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

}  // namespace

struct GpioEncoder::Impl {
  ChipPtr chip;
  std::array<gpiod_line*, kEncoderLines> lines{};  // owned by the chip; nullptr: no index line
  std::array<int, kEncoderLines> fds{-1, -1, -1};
  EdgeTracker tracker;
  std::string description;

  Impl(ChipPtr c, std::array<gpiod_line*, kEncoderLines> l, std::array<int, kEncoderLines> f, EdgeTracker t,
       std::string d)
      : chip(std::move(c)), lines(l), fds(f), tracker(t), description(std::move(d)) {}

  // Reads every line's FIFO; returns the time after which each was found empty (or its stage full).
  std::uint64_t read_events() noexcept;
  void start_level_check() noexcept;
};

std::uint64_t GpioEncoder::Impl::read_events() noexcept {
  std::array<gpiod_line_event, kKernelFifo> buffer{};
  std::uint64_t complete = UINT64_MAX;
  for (std::size_t i = 0; i < kEncoderLines; ++i) {
    if (fds[i] < 0) continue;
    const auto line = static_cast<EncoderLine>(i);
    for (;;) {
      // Always ask for a whole FIFO: only then does a full answer prove the FIFO was full. With less room the
      // events wait in the kernel (and a FIFO that fills meanwhile still shows as full on a later read).
      if (tracker.room(line) < kKernelFifo) {
        complete = std::min(complete, tracker.newest_staged_ns(line));
        break;
      }
      const std::uint64_t before = static_cast<std::uint64_t>(monotonic_ns());
      const int n = gpiod_line_event_read_fd_multiple(fds[i], buffer.data(), kKernelFifo);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK) tracker.note_read_error();
        complete = std::min(complete, before);
        break;
      }
      for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
        tracker.stage(line, LineEvent{to_ns(buffer[k].ts), buffer[k].event_type == GPIOD_LINE_EVENT_RISING_EDGE});
      }
      if (static_cast<unsigned>(n) < kKernelFifo) {
        // The read stops only when the FIFO is empty or our buffer full: all that was queued before it is here.
        complete = std::min(complete, before);
        break;
      }
      tracker.note_fifo_full();
    }
  }
  return complete;
}

void GpioEncoder::Impl::start_level_check() noexcept {
  const std::uint64_t lo = static_cast<std::uint64_t>(monotonic_ns());
  const int a = gpiod_line_get_value(lines[0]);
  const int b = gpiod_line_get_value(lines[1]);
  const std::uint64_t hi = static_cast<std::uint64_t>(monotonic_ns());
  if (a < 0 || b < 0) {
    tracker.note_read_error();
    return;
  }
  tracker.begin_level_check(fw::ab(a != 0, b != 0), lo, hi);
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
    fds[i] = gpiod_line_event_get_fd(line);
    // A drain must never wait for an edge.
    const int fl = ::fcntl(fds[i], F_GETFL);
    if (fl < 0 || ::fcntl(fds[i], F_SETFL, fl | O_NONBLOCK) < 0) {
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
  return GpioEncoder(std::make_unique<Impl>(std::move(chip), lines, fds, tracker, std::move(description)));
}

fw::EdgeDrain GpioEncoder::drain_edges(fw::EncoderEdge* out, std::size_t capacity) noexcept {
  if (!impl_) return {};
  const std::uint64_t read_empty_at = impl_->read_events();
  const fw::EdgeDrain drain = impl_->tracker.deliver(out, capacity, read_empty_at);
  if (impl_->tracker.wants_level_check()) impl_->start_level_check();
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
