// EdgeTracker on hand-made event sequences: the merge, and each way it finds (or must not invent) a loss.
#include <catch2/catch.hpp>
#include <vector>

#include "lever/board/edge_tracker.hpp"

using lever::board::EdgeTracker;
using lever::board::EncoderLine;
using lever::board::LineEvent;
using lever::fw::ab;
using lever::fw::AbState;
using lever::fw::EncoderEdge;

namespace {

constexpr std::uint64_t kOpen = 1'000;  // the values at open were read by this time
constexpr std::uint64_t kMargin = 50;   // ns, small so the tests' times stay readable
constexpr EncoderLine A = EncoderLine::a, B = EncoderLine::b, Z = EncoderLine::z;

struct Drained {
  std::vector<EncoderEdge> edges;
  std::uint32_t lost = 0;
};

// `read_empty_at`: when the reads found every line's FIFO empty.
Drained drain(EdgeTracker& t, std::uint64_t read_empty_at, std::size_t capacity = 64) {
  std::vector<EncoderEdge> out(capacity);
  const auto d = t.deliver(out.data(), capacity, read_empty_at);
  out.resize(d.count);
  return {out, d.lost};
}

std::vector<AbState> levels_of(const Drained& d) {
  std::vector<AbState> v;
  for (const auto& e : d.edges) v.push_back(e.levels);
  return v;
}

}  // namespace

TEST_CASE("edges of both lines come out merged by kernel time, as the levels after each") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  // Staged line by line, as the reads find them: A's events first, then B's.
  t.stage(A, {2'000, true});
  t.stage(A, {4'000, false});
  t.stage(B, {1'500, true});
  t.stage(B, {3'000, false});
  const auto d = drain(t, 5'000);
  CHECK(d.lost == 0);
  // 00 -> 01 -> 11 -> 10 -> 00: one forward cycle.
  CHECK(levels_of(d) == std::vector<AbState>{ab(0, 1), ab(1, 1), ab(1, 0), ab(0, 0)});
  CHECK(t.stats().edges == 4);
}

TEST_CASE("an edge newer than the reads are complete waits, so an older one of the other line goes first") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  // B's edge (3'000) was read; A's older one landed in its FIFO just after A had been read empty at 3'020,
  // within the margin of B's.
  t.stage(B, {3'000, true});
  auto d = drain(t, 3'020);
  CHECK(d.edges.empty());
  CHECK_FALSE(t.wants_level_check());
  t.stage(A, {2'990, true});
  d = drain(t, 4'000);
  CHECK(d.lost == 0);
  // 00 -> 10 -> 11: two steps back, as the lines moved.
  CHECK(levels_of(d) == std::vector<AbState>{ab(1, 0), ab(1, 1)});
}

TEST_CASE("a drain with too little room leaves the rest, in order, for the next") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  t.stage(B, {1'500, true});
  t.stage(A, {2'000, true});
  t.stage(B, {3'000, false});
  auto first = drain(t, 4'000, 2);
  CHECK(levels_of(first) == std::vector<AbState>{ab(0, 1), ab(1, 1)});
  CHECK_FALSE(t.wants_level_check());
  auto second = drain(t, 4'000, 2);
  CHECK(levels_of(second) == std::vector<AbState>{ab(1, 0)});
  CHECK(first.lost + second.lost == 0);
}

TEST_CASE("two rising edges in a row on one line are a loss") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  t.stage(A, {2'000, true});
  t.stage(A, {3'000, true});
  const auto d = drain(t, 4'000);
  CHECK(d.lost == 1);
  CHECK(t.stats().impossible == 1);
  CHECK(levels_of(d) == std::vector<AbState>{ab(1, 0), ab(1, 0)});
}

TEST_CASE("an edge older than one already delivered is a loss: the pair's order is unknown") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  t.stage(B, {3'000, true});
  CHECK(drain(t, 3'500).lost == 0);
  t.stage(A, {2'000, true});
  CHECK(drain(t, 5'000).lost == 1);
  CHECK(t.stats().reordered == 1);
}

TEST_CASE("a full kernel FIFO is reported as a loss on the next drain") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  t.note_fifo_full();
  CHECK(drain(t, 2'000).lost == 1);
  CHECK(drain(t, 3'000).lost == 0);
  CHECK(t.stats().fifo_full == 1);
}

TEST_CASE("edges racing the values read at open neither move the level twice nor count as lost") {
  EdgeTracker t(ab(true, false), kOpen, kMargin);  // A read high: its rising edge came just before
  t.stage(A, {kOpen - 10, true});
  t.stage(B, {kOpen + 20, true});  // within the margin, and not yet in the value read: it moves B
  const auto d = drain(t, 2'000);
  CHECK(d.lost == 0);
  CHECK(levels_of(d) == std::vector<AbState>{ab(1, 1)});
}

TEST_CASE("index rises come out at their place in time, with the levels of that moment") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  t.stage(B, {2'000, true});
  t.stage(Z, {2'500, true});
  t.stage(A, {3'000, true});
  const auto d = drain(t, 4'000);
  REQUIRE(d.edges.size() == 3);
  CHECK_FALSE(d.edges[0].index);
  CHECK(d.edges[1].index);
  CHECK(d.edges[1].levels == ab(0, 1));
  CHECK_FALSE(d.edges[2].index);
  CHECK(t.stats().index_edges == 1);
}

TEST_CASE("level check: values that agree pass, judged on the next drain") {
  EdgeTracker t(ab(false, true), kOpen, kMargin);
  CHECK(drain(t, 2'000).lost == 0);
  REQUIRE(t.wants_level_check());
  t.begin_level_check(ab(false, true), 2'100, 2'200);
  CHECK_FALSE(t.wants_level_check());
  CHECK(drain(t, 3'000).lost == 0);
  CHECK(t.stats().level_checks == 1);
  CHECK(t.wants_level_check());
}

TEST_CASE("level check: a line that disagrees is a loss, re-synced once, with an edge carrying the levels") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  drain(t, 2'000);
  t.begin_level_check(ab(false, true), 2'100, 2'200);  // B's rising edge never came
  const auto d = drain(t, 3'000);
  CHECK(d.lost == 1);
  CHECK(levels_of(d) == std::vector<AbState>{ab(0, 1)});
  CHECK(t.stats().resyncs == 1);
  CHECK(t.levels() == ab(0, 1));
  // Reported once: the next check agrees.
  t.begin_level_check(ab(false, true), 3'100, 3'200);
  CHECK(drain(t, 4'000).lost == 0);
  // The next edge on B is a falling one, and fits.
  t.stage(B, {4'500, false});
  CHECK(drain(t, 5'000).lost == 0);
}

TEST_CASE("level check: an edge that reaches the FIFO after the values were read is no loss") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  drain(t, 2'000);
  // B rose at 2'050 and is already in the value read at 2'100..2'200, but its event was not yet read.
  t.begin_level_check(ab(false, true), 2'100, 2'200);
  t.stage(B, {2'050, true});
  const auto d = drain(t, 3'000);
  CHECK(d.lost == 0);
  CHECK(levels_of(d) == std::vector<AbState>{ab(0, 1)});
  CHECK(t.stats().resyncs == 0);
}

TEST_CASE("level check: a line that moved inside the read's window may show either level") {
  for (const bool read_value : {false, true}) {
    EdgeTracker t(ab(false, false), kOpen, kMargin);
    drain(t, 2'000);
    t.begin_level_check(ab(read_value, false), 2'100, 2'200);
    t.stage(A, {2'150, true});
    CHECK(drain(t, 3'000).lost == 0);
  }
}

TEST_CASE("level check: an edge after the window does not make the earlier read wrong") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  drain(t, 2'000);
  t.begin_level_check(ab(false, false), 2'100, 2'200);
  t.stage(A, {2'600, true});  // after hi + margin
  const auto d = drain(t, 3'000);
  CHECK(d.lost == 0);
  CHECK(levels_of(d) == std::vector<AbState>{ab(1, 0)});
}

TEST_CASE("level check: waits while edges of its window may still be on their way") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  drain(t, 2'000);
  t.begin_level_check(ab(false, true), 2'100, 2'200);
  // Reads not complete past the window's end (hi + margin = 2'250, plus the margin for edges on their way)
  // cannot judge it.
  CHECK(drain(t, 2'290).lost == 0);
  CHECK(t.level_check_pending());
  // Nor can a drain that still holds an edge of the window (no room to deliver it).
  t.stage(B, {2'150, true});
  CHECK(drain(t, 3'000, 0).lost == 0);
  CHECK(t.level_check_pending());
  CHECK(drain(t, 3'000).lost == 0);
  CHECK_FALSE(t.level_check_pending());
}

TEST_CASE("level check: a loss that a later contradicting edge reports is not reported again") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  drain(t, 2'000);
  t.begin_level_check(ab(true, false), 2'100, 2'200);  // A rose, its event lost
  // A fell (lost too) and rose again: tracked A is still low, so this rising edge fits; the check alone reports.
  t.stage(A, {2'600, true});
  auto d = drain(t, 3'000);
  CHECK(d.lost == 1);
  CHECK(t.stats().resyncs == 0);  // the later edge set A's level already

  EdgeTracker u(ab(false, false), kOpen, kMargin);
  drain(u, 2'000);
  u.begin_level_check(ab(true, false), 2'100, 2'200);  // A rose, its event lost
  u.stage(A, {2'600, false});                          // A falls: falling on a low A contradicts
  d = drain(u, 3'000);
  CHECK(d.lost == 1);
  CHECK(u.stats().impossible == 1);
  CHECK(u.stats().level_checks == 1);
}

TEST_CASE("ab_events moves with every A/B edge applied and every re-sync, never with an index rise") {
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  t.stage(A, {kOpen - 10, false});  // absorbed by the settle window: no edge out, but the line's time moved
  drain(t, 2'000);
  CHECK(t.ab_events() == 1);
  t.stage(Z, {2'100, true});
  drain(t, 3'000);
  CHECK(t.ab_events() == 1);
  t.stage(B, {3'100, true});
  drain(t, 4'000);
  CHECK(t.ab_events() == 2);
  t.begin_level_check(ab(true, true), 4'100, 4'200);  // A's rise never came
  CHECK(drain(t, 5'000).lost == 1);
  CHECK(t.ab_events() == 3);
}

TEST_CASE("level check begun drains after its values were read: judged as a read at that time") {
  // As GpioEncoder does it: asked for after the drain at 2'000, read at 2'100..2'200 on another thread, begun
  // two drains later, none of which delivered an A/B edge.
  SECTION("values that agree pass") {
    EdgeTracker t(ab(false, true), kOpen, kMargin);
    drain(t, 2'000);
    const auto asked = t.ab_events();
    drain(t, 3'000);
    drain(t, 4'000);
    REQUIRE(t.ab_events() == asked);
    REQUIRE(t.wants_level_check());
    t.begin_level_check(ab(false, true), 2'100, 2'200);
    CHECK(drain(t, 5'000).lost == 0);
    CHECK(t.stats().level_checks == 1);
  }
  SECTION("a line that disagrees is a loss, re-synced") {
    EdgeTracker t(ab(false, false), kOpen, kMargin);
    drain(t, 2'000);
    drain(t, 3'000);
    t.begin_level_check(ab(false, true), 2'100, 2'200);
    const auto d = drain(t, 4'000);
    CHECK(d.lost == 1);
    CHECK(levels_of(d) == std::vector<AbState>{ab(0, 1)});
  }
  SECTION("an edge inside the window that reaches the FIFO only after the check began is no loss") {
    EdgeTracker t(ab(false, false), kOpen, kMargin);
    drain(t, 2'000);
    drain(t, 3'000);
    t.begin_level_check(ab(false, true), 2'100, 2'200);
    t.stage(B, {2'150, true});
    CHECK(drain(t, 4'000).lost == 0);
    CHECK(t.stats().resyncs == 0);
  }
}

TEST_CASE("values read before an A/B edge that was delivered since judge only the line that stood still") {
  // GpioEncoder drops such an answer anyway (ab_events() moved); were one begun, the line that moved after the
  // read counts as moved in its window, so the old value cannot fail on it, while the other line is judged.
  EdgeTracker t(ab(false, false), kOpen, kMargin);
  drain(t, 2'000);
  const auto asked = t.ab_events();
  t.stage(A, {2'600, true});
  CHECK(drain(t, 3'000).lost == 0);
  CHECK(t.ab_events() != asked);
  t.begin_level_check(ab(false, true), 2'100, 2'200);  // A low as it was then; B high: its rise never came
  const auto d = drain(t, 4'000);
  CHECK(d.lost == 1);
  CHECK(levels_of(d) == std::vector<AbState>{ab(1, 1)});
}
