// The epochs (peer_session.hpp, docs/datagram-format.md "Restarts"): two bridges exchange datagrams through
// PeerSessions; either or both restart; recordings made before a restart are replayed. Each end is a session, its
// sequence counter and what it has sent, with the datagram reduced to the three fields the session reads.
#include <catch2/catch.hpp>
#include <cstdint>
#include <set>
#include <vector>

#include "key.hpp"
#include "peer_session.hpp"

using namespace lever::bridge;

namespace {

struct Sent {
  std::uint64_t sequence, epoch, peer_epoch;
};

// One run of a bridge. Sequence numbers start at the "wall clock" given, as the relay's do.
struct End {
  PeerSession<1024> session;
  std::uint64_t next_sequence;
  std::vector<Sent> sent;  // everything it sent: what an attacker on the path records

  End(std::uint64_t epoch, std::uint64_t clock_us) : session(epoch), next_sequence(clock_us) {}
  Sent send() {
    sent.push_back({next_sequence++, session.own_epoch(), session.peer_epoch()});
    return sent.back();
  }
  AdmissionResult receive(const Sent& d) { return session.admit(d.sequence, d.epoch, d.peer_epoch); }
};

// Messages back and forth until `to` takes one from `from` as fresh; returns how many datagrams it took (both
// directions), or -1 after 10.
int handshake(End& from, End& to) {
  for (int n = 1; n <= 10; ++n) {
    if (to.receive(from.send()).fresh()) return 2 * n - 1;
    from.receive(to.send());
  }
  return -1;
}

int fresh_count(End& receiver, const std::vector<Sent>& recording) {
  int fresh = 0;
  for (const auto& d : recording) fresh += receiver.receive(d).fresh() ? 1 : 0;
  return fresh;
}

}  // namespace

TEST_CASE("epochs are random, 64 bits and never 0", "[bridge][epoch]") {
  std::set<std::uint64_t> seen;
  for (int i = 0; i < 1000; ++i) {
    const auto epoch = generate_epoch();
    CHECK(epoch != 0);
    seen.insert(epoch);
  }
  CHECK(seen.size() == 1000);
}

TEST_CASE("first contact: fresh from the second datagram on, each way", "[bridge][epoch]") {
  End a(0xA1, 1'000'000), b(0xB1, 2'000'000);
  // A's first datagram echoes nothing: stale, but it teaches B A's epoch.
  const auto first = b.receive(a.send());
  CHECK(first.admission == Admission::stale);
  CHECK(first.peer_epoch_changed);
  CHECK(b.session.peer_epoch() == 0xA1);
  // B's answer echoes A's epoch: fresh at once; then A's next echoes B's.
  const auto answer = a.receive(b.send());
  CHECK(answer.fresh());
  CHECK(answer.peer_epoch_changed);
  CHECK(b.receive(a.send()).fresh());
  CHECK_FALSE(b.receive(a.send()).peer_epoch_changed);  // learned once
}

TEST_CASE("a restarted receiver takes nothing recorded before it started", "[bridge][epoch][restart]") {
  End a(0xA1, 1'000'000), b(0xB1, 2'000'000);
  REQUIRE(handshake(a, b) > 0);
  const std::size_t before = a.sent.size();
  for (int i = 0; i < 100; ++i) REQUIRE(b.receive(a.send()).fresh());
  const std::vector<Sent> recording(a.sent.begin() + static_cast<std::ptrdiff_t>(before), a.sent.end());

  // B restarts: a new epoch and an empty window. Without the epoch check all 100 would be taken again.
  b = End(0xB2, 3'000'000);
  int stale = 0;
  for (const auto& d : recording) {
    const auto r = b.receive(d);
    CHECK_FALSE(r.fresh());
    stale += r.admission == Admission::stale ? 1 : 0;
  }
  CHECK(stale == 100);                    // authentic and new to the window, so stale rather than duplicate
  CHECK(fresh_count(b, recording) == 0);  // and a second replay meets the window

  SECTION("genuine traffic flows again after one exchange: B's datagram, then A's echo") {
    const auto from_b = a.receive(b.send());
    CHECK(from_b.peer_epoch_changed);  // A learns B's new epoch (B's sequence numbers moved on with its clock)
    CHECK(a.session.peer_epoch() == 0xB2);
    CHECK(b.receive(a.send()).fresh());
    CHECK(fresh_count(b, recording) == 0);  // the recording is still refused afterwards
  }
  SECTION("the recording replayed again after the handshake is still refused") {
    REQUIRE(handshake(a, b) > 0);
    CHECK(fresh_count(b, recording) == 0);
  }
}

TEST_CASE("a restarted sender is taken once it echoes; its old datagrams are not", "[bridge][epoch][restart]") {
  End a(0xA1, 1'000'000), b(0xB1, 2'000'000);
  REQUIRE(handshake(a, b) > 0);
  for (int i = 0; i < 50; ++i) REQUIRE(b.receive(a.send()).fresh());
  const std::vector<Sent> recording = a.sent;

  // A restarts a second later: its clock, and so its first sequence number, is past every number it used.
  a = End(0xA2, 2'000'000);
  const auto first = b.receive(a.send());
  CHECK(first.admission == Admission::stale);  // A does not know B's epoch yet
  CHECK(first.peer_epoch_changed);
  CHECK(a.receive(b.send()).fresh());  // B echoes A's new epoch at once
  CHECK(b.receive(a.send()).fresh());
  // A's first run echoed B's current epoch, but the window is past all of it.
  for (const auto& d : recording) {
    const auto r = b.receive(d);
    CHECK_FALSE(r.fresh());
    CHECK(r.admission != Admission::stale);
  }
  CHECK(b.session.peer_epoch() == 0xA2);  // and none of it rolled the learned epoch back
}

TEST_CASE("both ends restart: each side's recordings are refused by the other", "[bridge][epoch][restart]") {
  End a(0xA1, 1'000'000), b(0xB1, 1'500'000);
  REQUIRE(handshake(a, b) > 0);
  REQUIRE(handshake(b, a) > 0);
  for (int i = 0; i < 20; ++i) {
    REQUIRE(b.receive(a.send()).fresh());
    REQUIRE(a.receive(b.send()).fresh());
  }
  const auto recorded_a = a.sent, recorded_b = b.sent;
  a = End(0xA2, 5'000'000);
  b = End(0xB2, 5'500'000);
  // Replays first, before either has heard from the other.
  CHECK(fresh_count(b, recorded_a) == 0);
  CHECK(fresh_count(a, recorded_b) == 0);
  // The replays taught each an old epoch of the other; genuine traffic, newer, replaces it.
  CHECK(b.session.peer_epoch() == 0xA1);
  const int exchanged = handshake(a, b);
  CHECK(exchanged == 3);  // A (stale: echoes nothing), B (teaches A), A (fresh)
  CHECK(b.session.peer_epoch() == 0xA2);
  CHECK(a.session.peer_epoch() == 0xB2);
  CHECK(a.receive(b.send()).fresh());
  CHECK(fresh_count(b, recorded_a) == 0);
  CHECK(fresh_count(a, recorded_b) == 0);
}

TEST_CASE("only the newest datagram teaches the peer's epoch; echo 0 is never fresh", "[bridge][epoch]") {
  PeerSession<1024> s(0x5E55);
  CHECK(s.admit(10'000, 0xA1, 0).admission == Admission::stale);
  CHECK(s.peer_epoch() == 0xA1);
  const auto late = s.admit(9'990, 0xA0, 0x5E55);  // reordered: fresh, but older than the newest
  CHECK(late.fresh());
  CHECK(late.replay.reordered_by == 10);
  CHECK_FALSE(late.peer_epoch_changed);
  CHECK(s.peer_epoch() == 0xA1);
  CHECK(s.admit(9'990, 0xA1, 0x5E55).admission == Admission::duplicate);
  CHECK(s.admit(10'000 - 1024, 0xA1, 0x5E55).admission == Admission::too_old);
  CHECK(s.admit(10'001, 0, 0x5E55).fresh());  // epoch 0 is never learned: it would echo as "none"
  CHECK(s.peer_epoch() == 0xA1);
  CHECK(s.admit(10'002, 0xA1, 0).admission == Admission::stale);
}
