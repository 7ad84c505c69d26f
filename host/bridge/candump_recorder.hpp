#pragma once
// Records the CAN frames the bridge relays to a can-utils log file, in exactly the format of `candump -L`, so that
// `canplayer -I FILE` replays it and `log2asc -I FILE -O OUT.asc IFACE...` converts it:
//
//   (1700000000.000123) vcan0 123#DEADBEEF
//   (1700000000.000200) vcan0 7FF#
//
// that is "(%010ld.%06ld) %s %03X#" and two uppercase hex digits per data byte (can-utils candump.c and lib.c
// sprint_canframe): seconds zero-padded to 10 digits, always 6 digits of microseconds (the tools read them with
// "%ld" as an integer, so "000123" must keep its zeros), one space, the interface name, one space, 3 hex digits of
// the 11-bit id, '#', and nothing after the '#' when dlc is 0. One '\n'-terminated line per frame.
//
// Each record carries its own interface name: frames seen on the bus under the local CAN interface, frames that
// arrived from the network under a configurable name (the bridge's business). canplayer replays a line to the
// interface named in it, or, given assignments such as `vcan1=vcan0`, only the lines whose name is assigned; so
// distinct names let a replay pick one direction. Names must be 1..15 printable characters without spaces, '/'
// or ':' (IFNAMSIZ, and canplayer stops at a longer one).
//
// Threads: the recorder has `rings` single-producer rings, one per relay thread, so that the two directions never
// share a cache line or a lock. record(ring, ...) is for ONE producer thread per ring at a time. It never blocks,
// never allocates and makes no system call: it copies the frame into a fixed-size slot of its ring and publishes
// it with one atomic store, or, when the ring is full, drops it and counts the drop. A writer thread
// (std::jthread) drains the rings, merging them by time stamp, formats the lines with fmt and writes them with
// write(2). flush() and stats() may be called from any thread.
//
// Order: the writer takes a record only once it was already there at its previous look (one poll_interval
// before), and among those always the one with the earliest time stamp. Records reach a ring a few microseconds
// after their time stamp (the relay records after the send), so lines come out in time-stamp order unless a
// relay thread stalls between stamp and record() for longer than poll_interval; a log reader must not rely on
// more. Within one ring the order is the ring's. flush() and the destructor write everything at once.
//
// Files: the constructor starts a fresh `path`. A non-empty regular file already there is first shifted away as in
// a rotation (to path.1, ...), so restarting the bridge does not truncate the last recording (with keep_files = 0
// it is replaced). With rotate_bytes > 0, when the next line would take the file past rotate_bytes, the file is
// fsynced and closed, path.N-1 becomes path.N ... path becomes path.1 (the oldest, path.<keep_files>, is deleted)
// and a new path is started. Files hold whole lines only, so each is a valid log on its own.
//
// Errors on the writer side (cannot open, disk full, fsync) never throw: they are counted in write_errors, the
// frames concerned in lost, and the last one is kept as text (last_error()). A write that fails half-way is cut
// back to the last whole line.
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "lever/protocol/can_frame.hpp"

namespace lever::bridge {

struct RecorderConfig {
  std::filesystem::path path;
  std::size_t queue_capacity = 65536;  // records (40 bytes each) per ring; rounded up to a power of two; > 0
  std::size_t rings = 1;               // producers (relay threads), each with a ring of its own; 1..kMaxRings
  std::uint64_t rotate_bytes = 0;      // 0 = never rotate
  int keep_files = 5;                  // rotated files kept: path.1 .. path.<keep_files>; 0..1000
  // How often the writer looks at the rings when it is idle; a line waits up to two of them before write(2).
  // 2 ms is 40 frames at 20 kHz, against 65536 slots of headroom (3.3 s). See writer_loop() for why it polls.
  std::chrono::milliseconds poll_interval{2};
};

struct RecorderStats {
  std::uint64_t recorded = 0;            // accepted by record() (queued); all rings
  std::uint64_t dropped_queue_full = 0;  // refused by record(): the ring was full
  std::uint64_t rejected = 0;            // refused by record(): id > 0x7FF, dlc > 8, bad name, timestamp < 0
  std::uint64_t written = 0;             // lines written to a file
  std::uint64_t lost = 0;                // accepted, but not written because of a write error
  std::uint64_t bytes_written = 0;       // over all files
  std::uint64_t rotations = 0;
  std::uint64_t write_errors = 0;  // failed open, write, fsync, rename or close calls
  // offered frames = recorded + dropped_queue_full + rejected; after flush(): recorded = written + lost.
};

class CandumpRecorder {
 public:
  // Longest line: "(" 20 digits "." 6 digits ") " 15 name " " 3 id "#" 16 data "\n".
  static constexpr std::size_t kMaxLineLength = 1 + 20 + 1 + 6 + 2 + 15 + 1 + 3 + 1 + 16 + 1;
  static constexpr std::size_t kMaxInterfaceName = 15;  // IFNAMSIZ - 1
  static constexpr std::size_t kMaxRings = 4;

  // Opens (creates) config.path and starts the writer thread. Throws std::runtime_error naming the path if the
  // file cannot be created or an existing one shifted away, std::invalid_argument for a bad config.
  explicit CandumpRecorder(RecorderConfig config);
  CandumpRecorder(const CandumpRecorder&) = delete;
  CandumpRecorder& operator=(const CandumpRecorder&) = delete;
  // Drains every accepted frame to the file, fsyncs and closes it. record() must not run concurrently.
  ~CandumpRecorder();

  // Queues one frame in ring `ring` (< rings; another is rejected). timestamp_us: wall clock (CLOCK_REALTIME) in
  // microseconds since the epoch. Returns false if the frame was dropped (ring full) or rejected (invalid); both
  // are counted. One producer thread per ring.
  bool record(std::size_t ring, std::int64_t timestamp_us, std::string_view iface,
              const protocol::CanFrame& frame) noexcept;
  // Ring 0.
  bool record(std::int64_t timestamp_us, std::string_view iface, const protocol::CanFrame& frame) noexcept {
    return record(0, timestamp_us, iface, frame);
  }

  // Blocks until every frame accepted before the call is written and fsynced (or counted as lost).
  void flush();

  RecorderStats stats() const noexcept;
  // The last write error ("cannot write '/var/log/x.log': No space left on device"), or "" if none.
  std::string last_error() const;
  // Each ring's capacity after rounding up.
  std::size_t capacity() const noexcept { return mask_ + 1; }
  const std::filesystem::path& path() const noexcept { return config_.path; }

 private:
  struct Record {
    std::int64_t timestamp_us;
    std::array<char, kMaxInterfaceName + 1> iface;  // NUL-terminated
    protocol::CanFrame frame;
  };

  static constexpr std::size_t kCacheLine = 64;

  // One producer's ring: the producer's cache line (its position, its copy of the writer's, its counters), then
  // the writer's.
  struct Ring {
    alignas(kCacheLine) std::atomic<std::uint64_t> head{0};  // next slot to fill; = recorded
    std::uint64_t tail_cache = 0;
    std::atomic<std::uint64_t> dropped{0};
    std::atomic<std::uint64_t> rejected{0};
    alignas(kCacheLine) std::atomic<std::uint64_t> tail{0};  // next slot to read
    std::uint64_t seen = 0;                                  // writer: head at its previous look
    std::unique_ptr<Record[]> slots;
  };

  void writer_loop(std::stop_token stop);
  // Writes the records there at the previous look in time-stamp order, or with `everything` all there now.
  void drain(bool everything);
  void append_line(const Record& record);
  void write_pending();
  void sync_file();
  void rotate();
  bool shift_files();
  int open_file(bool truncate);  // 0 or the errno
  void close_file();
  void note_error(std::string_view what, std::string_view file, int error) noexcept;

  const RecorderConfig config_;
  const std::size_t mask_;
  const std::unique_ptr<Ring[]> rings_;
  std::atomic<std::uint64_t> rejected_bad_ring_{0};

  // Consumer side (writer thread).
  alignas(kCacheLine) std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> lost_{0};
  std::atomic<std::uint64_t> bytes_written_{0};
  std::atomic<std::uint64_t> rotations_{0};
  std::atomic<std::uint64_t> write_errors_{0};
  // Owned by the writer thread (and by the constructor before it starts).
  int fd_ = -1;
  std::uint64_t file_bytes_ = 0;        // size of the current file
  std::uint64_t rotate_threshold_ = 0;  // rotate when the file would exceed this (moved on after a failed rotation)
  std::vector<char> pending_;           // formatted lines not yet written; whole lines
  std::uint64_t pending_lines_ = 0;

  // flush() hand-shake and the error text; never touched by record().
  mutable std::mutex mutex_;
  std::condition_variable_any wake_;   // wakes the writer: flush requested (stop requests wake it by themselves)
  std::condition_variable synced_cv_;  // tells flush() callers that synced_ moved
  std::uint64_t flush_requests_ = 0;   // flush() calls so far; each one waits for its number in synced_
  std::uint64_t synced_ = 0;           // flush requests whose frames are written and fsynced (or lost)
  std::string last_error_;

  std::jthread writer_;  // last: started when everything above exists, joined in the destructor
};

}  // namespace lever::bridge
