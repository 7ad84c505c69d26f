// The candump recorder: single-producer rings filled by the relay threads, drained by a writer thread into a
// can-utils log file (see candump_recorder.hpp for the format and the rules).
#include "candump_recorder.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace lever::bridge {

namespace fs = std::filesystem;

namespace {

// Lines are formatted into this buffer and written with one write(2) when it is full or the ring is empty.
constexpr std::size_t kPendingBytes = 64 * 1024;
// Slots are handed back to the producer after this many lines are formatted, not only after a whole drain.
constexpr std::uint64_t kReleaseChunk = 256;
constexpr std::size_t kMaxQueueCapacity = std::size_t{1} << 30;
constexpr int kMaxKeepFiles = 1000;  // a rotation renames each of them

RecorderConfig validated(RecorderConfig config) {
  if (config.path.empty()) throw std::invalid_argument("candump recorder: no file name given");
  if (config.queue_capacity == 0 || config.queue_capacity > kMaxQueueCapacity)
    throw std::invalid_argument(fmt::format("candump recorder: queue_capacity must be 1..{}, not {}", kMaxQueueCapacity,
                                            config.queue_capacity));
  if (config.keep_files < 0 || config.keep_files > kMaxKeepFiles)
    throw std::invalid_argument(
        fmt::format("candump recorder: keep_files must be 0..{}, not {}", kMaxKeepFiles, config.keep_files));
  if (config.rings == 0 || config.rings > CandumpRecorder::kMaxRings)
    throw std::invalid_argument(
        fmt::format("candump recorder: rings must be 1..{}, not {}", CandumpRecorder::kMaxRings, config.rings));
  if (config.poll_interval.count() <= 0)
    throw std::invalid_argument("candump recorder: poll_interval must be positive");
  return config;
}

// A name canplayer and the kernel accept: 1..15 printable ASCII characters, no space, '/' or ':'.
bool valid_interface_name(std::string_view name) noexcept {
  if (name.empty() || name.size() > CandumpRecorder::kMaxInterfaceName) return false;
  for (const char c : name) {
    if (c <= ' ' || c > '~' || c == '/' || c == ':') return false;
  }
  return true;
}

std::string numbered(const fs::path& base, int n) { return fmt::format("{}.{}", base.string(), n); }

}  // namespace

CandumpRecorder::CandumpRecorder(RecorderConfig config)
    : config_(validated(std::move(config))),
      mask_(std::bit_ceil(config_.queue_capacity) - 1),
      rings_(std::make_unique<Ring[]>(config_.rings)),
      rotate_threshold_(config_.rotate_bytes) {
  pending_.reserve(kPendingBytes);
  // Value-initialised, so every page of the rings is touched here and record() never takes a page fault.
  for (std::size_t i = 0; i < config_.rings; ++i) rings_[i].slots = std::make_unique<Record[]>(mask_ + 1);

  // Never write through a symlink or at a directory (lever-bridge refuses devices too, at configuration time; the
  // recorder writes to one, /dev/full in its tests, but never renames it: see shift_files()).
  if (struct stat st{}; ::lstat(config_.path.c_str(), &st) == 0 && (S_ISLNK(st.st_mode) || S_ISDIR(st.st_mode))) {
    throw std::invalid_argument(fmt::format("candump recorder: '{}' is a {}; the log is a file of its own",
                                            config_.path.string(), S_ISLNK(st.st_mode) ? "symlink" : "directory"));
  }
  // Never truncate a previous recording: shift it away as a rotation would.
  std::error_code ec;
  if (fs::is_regular_file(config_.path, ec) && fs::file_size(config_.path, ec) > 0 && !ec) {
    if (!shift_files())
      throw std::runtime_error(
          fmt::format("candump recorder: cannot move the existing log file aside: {}", last_error_));
  }
  if (const int error = open_file(/*truncate=*/true); error != 0)
    throw std::runtime_error(fmt::format("candump recorder: cannot create the log file '{}': {}", config_.path.string(),
                                         std::generic_category().message(error)));

  try {
    writer_ = std::jthread([this](std::stop_token stop) { writer_loop(std::move(stop)); });
  } catch (...) {  // no thread (std::system_error): no destructor will close the file
    close_file();
    throw;
  }
}

CandumpRecorder::~CandumpRecorder() {
  writer_.request_stop();
  if (writer_.joinable()) writer_.join();  // the writer drains, fsyncs and closes before it returns
  close_file();                            // in case it could not
}

// ---- Producer (relay thread) ----

bool CandumpRecorder::record(std::size_t ring_index, std::int64_t timestamp_us, std::string_view iface,
                             const protocol::CanFrame& frame) noexcept {
  if (ring_index >= config_.rings) {
    rejected_bad_ring_.fetch_add(1, std::memory_order_relaxed);  // a caller's bug; never on the relay's path
    return false;
  }
  Ring& ring = rings_[ring_index];
  // Counters owned by this ring's producer: a plain load and store, no locked read-modify-write.
  const auto bump = [](std::atomic<std::uint64_t>& counter) {
    counter.store(counter.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  };
  if (frame.id > protocol::kMaxStandardId || frame.dlc > frame.data.size() || timestamp_us < 0 ||
      !valid_interface_name(iface)) {
    bump(ring.rejected);
    return false;
  }
  const std::uint64_t head = ring.head.load(std::memory_order_relaxed);
  if (head - ring.tail_cache > mask_) {
    // Looks full from the last known consumer position: look again (the only access to the writer's cache line).
    ring.tail_cache = ring.tail.load(std::memory_order_acquire);
    if (head - ring.tail_cache > mask_) {
      bump(ring.dropped);
      return false;
    }
  }
  Record& slot = ring.slots[static_cast<std::size_t>(head & mask_)];
  slot.timestamp_us = timestamp_us;
  std::memcpy(slot.iface.data(), iface.data(), iface.size());
  slot.iface[iface.size()] = '\0';
  slot.frame = frame;
  ring.head.store(head + 1, std::memory_order_release);  // publishes the slot
  return true;
}

// ---- Any thread ----

void CandumpRecorder::flush() {
  std::unique_lock lock(mutex_);
  // The writer drains every ring after it has seen this request under the mutex, so it sees every record
  // accepted before this call.
  const std::uint64_t request = ++flush_requests_;
  wake_.notify_all();
  synced_cv_.wait(lock, [&] { return synced_ >= request; });
}

RecorderStats CandumpRecorder::stats() const noexcept {
  RecorderStats s;
  s.rejected = rejected_bad_ring_.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < config_.rings; ++i) {
    s.recorded += rings_[i].head.load(std::memory_order_acquire);
    s.dropped_queue_full += rings_[i].dropped.load(std::memory_order_relaxed);
    s.rejected += rings_[i].rejected.load(std::memory_order_relaxed);
  }
  s.written = written_.load(std::memory_order_relaxed);
  s.lost = lost_.load(std::memory_order_relaxed);
  s.bytes_written = bytes_written_.load(std::memory_order_relaxed);
  s.rotations = rotations_.load(std::memory_order_relaxed);
  s.write_errors = write_errors_.load(std::memory_order_relaxed);
  return s;
}

std::string CandumpRecorder::last_error() const {
  std::lock_guard lock(mutex_);
  return last_error_;
}

// ---- Writer thread ----

void CandumpRecorder::writer_loop(std::stop_token stop) {
  // Why the writer polls instead of being woken by record(): waking a sleeping thread is a futex system call (a
  // condition variable's notify, or atomic::notify, whenever the writer waits, which is nearly always), and it can
  // put the woken writer on the relay thread's core. Measured 2026-11 on the 2-core build machine under load:
  // notify_one to a waiting thread, one call per 20 us, took 6-10 us on average and up to 0.2-4 ms, against
  // 30-50 ns for a whole record(). A poll costs the relay thread nothing: record() is a copy and one atomic store.
  // The price: a line reaches write(2) up to poll_interval (2 ms) late, which a log does not mind; the ring must
  // hold poll_interval of traffic (40 frames at 20 kHz, against 65536 slots); and 500 wake-ups a second when idle.
  // flush() and the destructor wake the writer at once, through wake_ and the stop token.
  for (;;) {
    try {
      // Read before draining: once stop is requested no record() runs any more, so this drain gets everything.
      const bool stopping = stop.stop_requested();
      std::uint64_t requested = 0;
      {
        std::lock_guard lock(mutex_);
        requested = flush_requests_;
      }
      const bool flush_wanted = requested > synced_;  // synced_ is written by this thread only
      drain(stopping || flush_wanted);
      if (stopping || flush_wanted) {
        sync_file();
        if (stopping) close_file();
        {
          std::lock_guard lock(mutex_);
          synced_ = requested;
        }
        synced_cv_.notify_all();
        if (stopping) return;
        continue;
      }
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, stop, config_.poll_interval, [this] { return flush_requests_ > synced_; });
    } catch (...) {
      // Nothing here should throw (formatting goes to a fixed buffer, pending_ never grows past its reserve);
      // if something does (bad_alloc building a file name), count it and go on rather than end the process.
      note_error("unexpected error while recording to", config_.path.native(), ENOMEM);
    }
  }
}

void CandumpRecorder::drain(bool everything) {
  const std::size_t count = config_.rings;
  std::array<std::uint64_t, kMaxRings> tails{}, ends{}, released{};
  for (std::size_t i = 0; i < count; ++i) {
    Ring& ring = rings_[i];
    tails[i] = released[i] = ring.tail.load(std::memory_order_relaxed);  // this thread's own position
    const std::uint64_t head = ring.head.load(std::memory_order_acquire);
    // Records published since the previous look wait for the next one, unless everything is wanted: a record of
    // the other ring with an earlier stamp may still be on its way (see the header).
    ends[i] = everything ? head : ring.seen;
    ring.seen = head;
  }
  for (;;) {
    // The earliest time stamp among the rings' next records (two rings: one comparison per line).
    std::size_t best = count;
    for (std::size_t i = 0; i < count; ++i) {
      if (tails[i] == ends[i]) continue;
      if (best == count || rings_[i].slots[static_cast<std::size_t>(tails[i] & mask_)].timestamp_us <
                               rings_[best].slots[static_cast<std::size_t>(tails[best] & mask_)].timestamp_us) {
        best = i;
      }
    }
    if (best == count) break;
    append_line(rings_[best].slots[static_cast<std::size_t>(tails[best] & mask_)]);
    if (++tails[best] - released[best] >= kReleaseChunk) {
      // The lines are copied out: the producer may reuse the slots, also in the middle of a long drain.
      rings_[best].tail.store(tails[best], std::memory_order_release);
      released[best] = tails[best];
    }
  }
  for (std::size_t i = 0; i < count; ++i) rings_[i].tail.store(tails[i], std::memory_order_release);
  write_pending();
}

void CandumpRecorder::append_line(const Record& record) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::array<char, kMaxLineLength> line;
  // candump.c: "(%010ld.%06ld) %*s %s\n"; lib.c sprint_canframe: "%03X#" then "%02X" per byte, uppercase.
  char* out = fmt::format_to(line.data(), "({:010}.{:06}) {} {:03X}#", record.timestamp_us / 1'000'000,
                             record.timestamp_us % 1'000'000, std::string_view(record.iface.data()), record.frame.id);
  for (std::size_t i = 0; i < record.frame.dlc; ++i) {
    const std::uint8_t byte = record.frame.data[i];
    *out++ = kHex[byte >> 4];
    *out++ = kHex[byte & 0x0F];
  }
  *out++ = '\n';
  const auto length = static_cast<std::size_t>(out - line.data());

  if (config_.rotate_bytes > 0) {
    const std::uint64_t before = file_bytes_ + pending_.size();
    // A line longer than rotate_bytes still goes into an empty file: files are never empty and never split lines.
    if (before > 0 && before + length > rotate_threshold_) {
      write_pending();
      rotate();
    }
  }
  if (pending_.size() + length > kPendingBytes) write_pending();
  pending_.insert(pending_.end(), line.data(), line.data() + length);  // within the reserve: no allocation
  ++pending_lines_;
}

void CandumpRecorder::write_pending() {
  if (pending_.empty()) return;
  if (fd_ < 0) open_file(/*truncate=*/false);  // reopen after a failure; append to whatever is there
  if (fd_ < 0) {
    lost_.fetch_add(pending_lines_, std::memory_order_relaxed);
    pending_.clear();
    pending_lines_ = 0;
    return;
  }
  std::size_t done = 0;
  int error = 0;
  while (done < pending_.size()) {
    const ssize_t n = ::write(fd_, pending_.data() + done, pending_.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      error = n < 0 ? errno : EIO;
      break;
    }
  }
  std::size_t kept = done;
  std::uint64_t lines = pending_lines_;
  if (done < pending_.size()) {
    // Keep whole lines only: cut the file back to the end of the last complete line (O_APPEND, so the next write
    // goes to the new end).
    const auto last_newline = std::find(
        std::make_reverse_iterator(pending_.begin() + static_cast<std::ptrdiff_t>(done)), pending_.rend(), '\n');
    kept = static_cast<std::size_t>(pending_.rend() - last_newline);
    lines = static_cast<std::uint64_t>(
        std::count(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(kept), '\n'));
    if (kept < done && ::ftruncate(fd_, static_cast<off_t>(file_bytes_ + kept)) != 0) {
      note_error("cannot cut a torn line from", config_.path.native(), errno);
    }
    note_error("cannot write", config_.path.native(), error);
    lost_.fetch_add(pending_lines_ - lines, std::memory_order_relaxed);
  }
  written_.fetch_add(lines, std::memory_order_relaxed);
  bytes_written_.fetch_add(kept, std::memory_order_relaxed);
  file_bytes_ += kept;
  pending_.clear();
  pending_lines_ = 0;
}

void CandumpRecorder::sync_file() {
  // EINVAL: not a file that can be synchronised (a pipe, /dev/null); nothing is lost.
  if (fd_ >= 0 && ::fsync(fd_) != 0 && errno != EINVAL) note_error("cannot fsync", config_.path.native(), errno);
}

void CandumpRecorder::rotate() {
  sync_file();  // flush() promises the frames are on disk, also those now in path.1
  close_file();
  if (!shift_files()) {
    // Keep appending to the same file rather than truncate it; try again after another rotate_bytes.
    open_file(/*truncate=*/false);
    rotate_threshold_ = file_bytes_ + config_.rotate_bytes;
    return;
  }
  rotations_.fetch_add(1, std::memory_order_relaxed);
  rotate_threshold_ = config_.rotate_bytes;
  open_file(/*truncate=*/true);
}

// path.<keep-1> -> path.<keep>, ..., path -> path.1 (path.<keep> deleted first). False if path stays in place.
bool CandumpRecorder::shift_files() {
  const fs::path& base = config_.path;
  // Only our own log moves: a device (or anything else put at the path since) stays where it is.
  if (struct stat st{}; ::lstat(base.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    note_error("will not rotate", base.native(), EINVAL);
    return false;
  }
  if (config_.keep_files == 0) {
    if (::unlink(base.c_str()) != 0 && errno != ENOENT) {
      note_error("cannot delete", base.native(), errno);
      return false;
    }
    return true;
  }
  try {
    const std::string oldest = numbered(base, config_.keep_files);
    if (::unlink(oldest.c_str()) != 0 && errno != ENOENT) note_error("cannot delete", oldest, errno);
    for (int i = config_.keep_files - 1; i >= 1; --i) {
      const std::string from = numbered(base, i);
      if (::rename(from.c_str(), numbered(base, i + 1).c_str()) != 0 && errno != ENOENT)
        note_error("cannot rename", from, errno);
    }
    if (::rename(base.c_str(), numbered(base, 1).c_str()) != 0 && errno != ENOENT) {
      note_error("cannot rename", base.native(), errno);
      return false;
    }
    return true;
  } catch (...) {  // bad_alloc for a file name
    note_error("cannot rotate", base.native(), ENOMEM);
    return false;
  }
}

int CandumpRecorder::open_file(bool truncate) {
  const int flags = O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW | (truncate ? O_TRUNC : 0);
  const int fd = ::open(config_.path.c_str(), flags, 0644);
  if (fd < 0) {
    const int error = errno;
    note_error("cannot open", config_.path.native(), error);
    return error;
  }
  struct stat st {};
  file_bytes_ =
      (!truncate && ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) ? static_cast<std::uint64_t>(st.st_size) : 0;
  fd_ = fd;
  return 0;
}

void CandumpRecorder::close_file() {
  if (fd_ < 0) return;
  if (::close(fd_) != 0) note_error("cannot close", config_.path.native(), errno);  // may report a failed write-back
  fd_ = -1;
}

void CandumpRecorder::note_error(std::string_view what, std::string_view file, int error) noexcept {
  write_errors_.fetch_add(1, std::memory_order_relaxed);
  try {
    std::string text = fmt::format("{} '{}': {}", what, file, std::generic_category().message(error));
    std::lock_guard lock(mutex_);
    last_error_ = std::move(text);
  } catch (...) {
    // Out of memory for the message: the counter still tells.
  }
}

}  // namespace lever::bridge
