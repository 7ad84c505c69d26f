#pragma once
// The decoding half of the libgpiod encoder backend, free of I/O so it can be tested on any machine: merges
// the per-line edge events of the GPIO v1 interface into one stream, keeps the A/B levels, and finds the
// edges the kernel lost without telling (its 16-event FIFO per line drops the newest when full).
//
// Merging: each line's events come from its own file, read one after the other, so an edge that lands on A
// just after A was read may be older than one read from B a moment later. The caller says when its reads
// found every line empty; edges newer than that, less the margin for edges still on their way from the
// interrupt to the FIFO, wait for the next drain, so the stream stays in time order.
//
// How a loss shows (each adds 1 to the `lost` the next drain reports):
//  - a read that came back with a whole FIFO's worth of events: the FIFO was full, so newer ones may be gone;
//  - an edge whose type contradicts the tracked level (two rising edges in a row on one line);
//  - an A/B edge older than one already delivered (it was on its way longer than the margin): the order of
//    the two lines' edges, and so the direction, is unknown;
//  - a level check that fails: the levels read from the lines disagree with what the edges say they were.
// A level check is timed, not immediate: the values are read at [lo, hi], and judged only once the reads are
// complete past hi plus the margin and every edge up to there is delivered, so an edge the reader merely saw
// late (still in the FIFO, or in flight between the interrupt and the FIFO) is no loss. A line that changed
// within the margin of the read may show either level. A failed check re-syncs the line to the level read and
// delivers one extra edge with the corrected levels, so one loss is reported once and the decoder downstream
// follows the lines again.
//
// The values may be read long before begin_level_check() is called (GpioEncoder reads them on a thread of its
// own): the check is as good as a read at the moment it was asked for as long as the values were read after
// that moment and ab_events() has not moved since (no A/B edge delivered, so nothing newer than the read is in
// the tracked levels).
#include <array>
#include <cstddef>
#include <cstdint>

#include "lever/fw/hal.hpp"

namespace lever::board {

enum class EncoderLine : std::uint8_t { a = 0, b = 1, z = 2 };
inline constexpr std::size_t kEncoderLines = 3;

struct LineEvent {
  std::uint64_t timestamp_ns = 0;  // CLOCK_MONOTONIC, as the v1 interface stamps events since Linux 5.7
  bool rising = false;
};

struct EdgeStats {
  std::uint64_t edges = 0;         // A/B edges delivered (each kernel event once)
  std::uint64_t index_edges = 0;   // Z rising edges delivered
  std::uint64_t lost = 0;          // sum of every drain's `lost`
  std::uint64_t fifo_full = 0;     // reads that emptied a full kernel FIFO
  std::uint64_t impossible = 0;    // edges contradicting the tracked level
  std::uint64_t reordered = 0;     // A/B edges older than one already delivered
  std::uint64_t level_checks = 0;  // level checks judged
  std::uint64_t resyncs = 0;       // level checks that failed and moved the tracked levels
  std::uint64_t read_errors = 0;   // failed reads of events or values (other than "nothing to read")
};

class EdgeTracker {
 public:
  static constexpr std::size_t kStageCapacity = 64;  // events per line waiting for delivery

  // `levels`: the A/B values read right after the lines were requested; `read_end_ns`: when that read ended.
  // Edges stamped up to read_end + margin may already be in those values: they set the level, never count as
  // a loss. `margin_ns`: how long an edge may take to show, from the level change to its stamp (interrupt
  // latency) and from its stamp to the FIFO (the kernel's interrupt thread).
  EdgeTracker(fw::AbState levels, std::uint64_t read_end_ns, std::uint64_t margin_ns) noexcept;

  std::size_t room(EncoderLine line) const noexcept;
  // One event as read from a line, in the order read (the kernel keeps each line's order). Refused (false)
  // when that line's stage is full; the caller reads only as much as room() allows.
  bool stage(EncoderLine line, const LineEvent& event) noexcept;
  void note_fifo_full() noexcept;
  void note_read_error() noexcept;

  // Up to `capacity` edges, oldest first by kernel time, then the verdict of a pending level check if it can
  // be judged now. `read_empty_at_ns`: the caller's reads found every line's FIFO empty at or after this time
  // (or the line's stage full up to it); edges stamped within the margin before it may still be on their way,
  // so only older ones go out.
  fw::EdgeDrain deliver(fw::EncoderEdge* out, std::size_t capacity, std::uint64_t read_empty_at_ns) noexcept;
  // The newest event staged for a line (0 if none): how far a line whose stage is full has been read.
  std::uint64_t newest_staged_ns(EncoderLine line) const noexcept;

  // True when a new level check may start: none pending and nothing staged.
  bool wants_level_check() const noexcept;
  void begin_level_check(fw::AbState values, std::uint64_t lo_ns, std::uint64_t hi_ns) noexcept;
  bool level_check_pending() const noexcept { return check_.pending; }
  // Every A/B edge applied (delivered, or absorbed by the settle window at open) and every re-sync: while it
  // stands still, the levels and edge times a level check starts from have not moved.
  std::uint64_t ab_events() const noexcept { return ab_events_; }

  fw::AbState levels() const noexcept { return fw::ab(level_[0], level_[1]); }
  const EdgeStats& stats() const noexcept { return stats_; }

 private:
  struct Stage {
    std::array<LineEvent, kStageCapacity> events{};
    std::size_t head = 0;
    std::size_t size = 0;
    const LineEvent& front() const noexcept { return events[head]; }
  };
  struct LevelCheck {
    bool pending = false;
    std::uint64_t lo = 0, hi = 0;              // the read's window, widened by the margin
    std::array<bool, 2> value{};               // A, B as read
    std::array<std::uint8_t, 2> seen{};        // per line, bit v set: the line was at level v in the window
    std::array<bool, 2> moved_after{};         // an edge on the line after the window
    std::array<bool, 2> contradicted_after{};  // ... and it contradicted the tracked level
  };

  void apply(EncoderLine line, const LineEvent& event, fw::EncoderEdge* out, std::size_t& count) noexcept;
  void judge_level_check(fw::EncoderEdge* out, std::size_t& count, std::size_t capacity,
                         std::uint64_t complete_until_ns) noexcept;
  void lose() noexcept;

  std::array<Stage, kEncoderLines> stage_{};
  std::array<bool, 2> level_{};
  std::array<std::uint64_t, 2> last_edge_ns_{};
  std::uint64_t last_ab_ns_ = 0;
  std::uint64_t settle_until_ns_;
  std::uint64_t margin_ns_;
  LevelCheck check_{};
  std::uint32_t pending_lost_ = 0;
  std::uint64_t ab_events_ = 0;
  EdgeStats stats_{};
};

}  // namespace lever::board
