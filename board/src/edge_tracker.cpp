#include "lever/board/edge_tracker.hpp"

namespace lever::board {

namespace {

constexpr std::uint8_t bit(bool level) noexcept { return level ? 2 : 1; }

}  // namespace

EdgeTracker::EdgeTracker(fw::AbState levels, std::uint64_t read_end_ns, std::uint64_t margin_ns) noexcept
    : settle_until_ns_(read_end_ns + margin_ns), margin_ns_(margin_ns) {
  level_[0] = (levels & 2u) != 0;
  level_[1] = (levels & 1u) != 0;
}

std::size_t EdgeTracker::room(EncoderLine line) const noexcept {
  return kStageCapacity - stage_[static_cast<std::size_t>(line)].size;
}

std::uint64_t EdgeTracker::newest_staged_ns(EncoderLine line) const noexcept {
  const Stage& s = stage_[static_cast<std::size_t>(line)];
  return s.size == 0 ? 0 : s.events[(s.head + s.size - 1) % kStageCapacity].timestamp_ns;
}

bool EdgeTracker::stage(EncoderLine line, const LineEvent& event) noexcept {
  Stage& s = stage_[static_cast<std::size_t>(line)];
  if (s.size == kStageCapacity) return false;
  s.events[(s.head + s.size) % kStageCapacity] = event;
  ++s.size;
  return true;
}

void EdgeTracker::lose() noexcept {
  if (pending_lost_ != UINT32_MAX) ++pending_lost_;
  ++stats_.lost;
}

void EdgeTracker::note_fifo_full() noexcept {
  ++stats_.fifo_full;
  lose();
}

void EdgeTracker::note_read_error() noexcept {
  // Whatever the failed read held is gone for us.
  ++stats_.read_errors;
  lose();
}

bool EdgeTracker::wants_level_check() const noexcept {
  if (check_.pending) return false;
  for (const Stage& s : stage_)
    if (s.size != 0) return false;
  return true;
}

void EdgeTracker::begin_level_check(fw::AbState values, std::uint64_t lo_ns, std::uint64_t hi_ns) noexcept {
  check_ = LevelCheck{};
  check_.pending = true;
  check_.lo = lo_ns > margin_ns_ ? lo_ns - margin_ns_ : 0;
  check_.hi = hi_ns + margin_ns_;
  check_.value = {(values & 2u) != 0, (values & 1u) != 0};
  for (std::size_t i = 0; i < 2; ++i) {
    // An edge just before the read (within the margin) may or may not be in the value read.
    const bool moved_in_window = last_edge_ns_[i] != 0 && last_edge_ns_[i] >= check_.lo;
    check_.seen[i] = moved_in_window ? 3 : bit(level_[i]);
  }
}

void EdgeTracker::apply(EncoderLine line, const LineEvent& event, fw::EncoderEdge* out, std::size_t& count) noexcept {
  if (line == EncoderLine::z) {
    if (!event.rising) return;  // only rising edges are requested on the index line
    out[count++] = fw::EncoderEdge{levels(), true};
    ++stats_.index_edges;
    return;
  }
  const std::size_t i = static_cast<std::size_t>(line);
  ++ab_events_;
  const bool before = level_[i];
  if (event.timestamp_ns <= settle_until_ns_) {
    // Raced with the values read at open: already counted in them or not, the type tells the level after it.
    level_[i] = event.rising;
    last_edge_ns_[i] = event.timestamp_ns;
    if (event.timestamp_ns > last_ab_ns_) last_ab_ns_ = event.timestamp_ns;
    if (before != event.rising) {
      out[count++] = fw::EncoderEdge{levels(), false};
      ++stats_.edges;
    }
    return;
  }
  if (event.timestamp_ns < last_ab_ns_) {
    // The other line's newer edge went out first: the decoded direction of this pair may be wrong.
    ++stats_.reordered;
    lose();
  } else {
    last_ab_ns_ = event.timestamp_ns;
  }
  const bool contradiction = event.rising == before;
  if (contradiction) {
    // The opposite edge between the two never reached us.
    ++stats_.impossible;
    lose();
  }
  level_[i] = event.rising;
  last_edge_ns_[i] = event.timestamp_ns;
  out[count++] = fw::EncoderEdge{levels(), false};
  ++stats_.edges;

  if (check_.pending) {
    if (event.timestamp_ns < check_.lo) {
      // Arrived late, but happened before the read: it sets the level the read should have seen.
      check_.seen[i] = bit(level_[i]);
    } else if (event.timestamp_ns <= check_.hi) {
      check_.seen[i] |= bit(level_[i]);
    } else {
      check_.moved_after[i] = true;
      check_.contradicted_after[i] = check_.contradicted_after[i] || contradiction;
    }
  }
}

void EdgeTracker::judge_level_check(fw::EncoderEdge* out, std::size_t& count, std::size_t capacity,
                                    std::uint64_t complete_until_ns) noexcept {
  if (!check_.pending) return;
  // Edges stamped inside the window may still be on their way.
  if (complete_until_ns < check_.hi) return;
  for (std::size_t i = 0; i < 2; ++i) {
    const Stage& s = stage_[i];
    if (s.size != 0 && s.front().timestamp_ns <= check_.hi) return;
  }
  bool resync = false;
  bool lost = false;
  for (std::size_t i = 0; i < 2; ++i) {
    if ((check_.seen[i] & bit(check_.value[i])) != 0) continue;
    // A later edge on this line that contradicted the level has reported this loss already, and its type
    // has set the level right.
    if (!check_.contradicted_after[i]) lost = true;
    if (!check_.moved_after[i]) resync = true;
  }
  if (resync && count >= capacity) return;  // judged on the next call, when there is room for the edge
  ++stats_.level_checks;
  check_.pending = false;
  if (lost) lose();
  if (!resync) return;
  for (std::size_t i = 0; i < 2; ++i) {
    if ((check_.seen[i] & bit(check_.value[i])) == 0 && !check_.moved_after[i]) level_[i] = check_.value[i];
  }
  ++stats_.resyncs;
  ++ab_events_;
  out[count++] = fw::EncoderEdge{levels(), false};
}

fw::EdgeDrain EdgeTracker::deliver(fw::EncoderEdge* out, std::size_t capacity,
                                   std::uint64_t read_empty_at_ns) noexcept {
  // Everything stamped up to here is staged, unless it took longer than the margin to reach its FIFO.
  const std::uint64_t complete_until_ns = read_empty_at_ns > margin_ns_ ? read_empty_at_ns - margin_ns_ : 0;
  std::size_t count = 0;
  while (count < capacity) {
    // Oldest head first; on a tie A before B before Z, which is as good as any order for equal times.
    std::size_t pick = kEncoderLines;
    for (std::size_t i = 0; i < kEncoderLines; ++i) {
      if (stage_[i].size == 0) continue;
      if (pick == kEncoderLines || stage_[i].front().timestamp_ns < stage_[pick].front().timestamp_ns) pick = i;
    }
    if (pick == kEncoderLines) break;
    // An older edge of another line may still come: this one waits for the next drain.
    if (stage_[pick].front().timestamp_ns > complete_until_ns) break;
    Stage& s = stage_[pick];
    const LineEvent event = s.front();
    s.head = (s.head + 1) % kStageCapacity;
    --s.size;
    apply(static_cast<EncoderLine>(pick), event, out, count);
  }
  judge_level_check(out, count, capacity, complete_until_ns);
  fw::EdgeDrain drain{count, pending_lost_};
  pending_lost_ = 0;
  return drain;
}

}  // namespace lever::board
