// The replay window: each authenticated sequence number once, within the window; reorders and gaps reported.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <limits>
#include <set>
#include <type_traits>

#include "lever/common/rng.hpp"
#include "replay_window.hpp"

using lever::bridge::ReplayResult;
using lever::bridge::ReplayVerdict;
using lever::bridge::ReplayWindow;

namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

// What the window must answer, from a complete record of what it accepted.
template <std::size_t Width>
class ReferenceWindow {
 public:
  ReplayResult accept(std::uint64_t s) {
    ReplayResult r;
    if (seen_.empty()) {
      newest_ = s;
    } else if (s > newest_) {
      r.gap = s - newest_ - 1;
      newest_ = s;
    } else if (newest_ - s >= Width) {
      return {ReplayVerdict::too_old, 0, 0};
    } else if (seen_.count(s) != 0) {
      return {ReplayVerdict::duplicate, 0, 0};
    } else {
      r.reordered_by = newest_ - s;
    }
    seen_.insert(s);
    return r;
  }

 private:
  std::set<std::uint64_t> seen_;
  std::uint64_t newest_ = 0;
};

template <std::size_t Width>
void check_against_reference(std::uint64_t seed, std::uint64_t start) {
  lever::Rng rng(seed);
  ReplayWindow<Width> window;
  ReferenceWindow<Width> reference;
  std::uint64_t cursor = start;
  for (int i = 0; i < 20000; ++i) {
    const auto choice = rng.next() % 100;
    std::uint64_t s = cursor;
    if (choice < 60) {
      s = cursor + 1 + rng.next() % 3;  // mostly forward, small gaps
    } else if (choice < 90) {
      s = cursor - std::min<std::uint64_t>(cursor, rng.next() % (Width + 80));  // late, duplicates, too old
    } else if (choice < 97) {
      s = cursor + rng.next() % (3 * Width);  // jumps around the window's width
    } else {
      s = cursor + (rng.next() >> 20);  // far jumps
    }
    if (s > cursor) cursor = s;
    const bool predicted = window.would_accept(s);
    const auto got = window.accept(s);
    const auto want = reference.accept(s);
    CAPTURE(i, s, window.newest());
    REQUIRE(got.verdict == want.verdict);
    REQUIRE(got.reordered_by == want.reordered_by);
    REQUIRE(got.gap == want.gap);
    REQUIRE(predicted == got.accepted());
  }
}

}  // namespace

TEST_CASE("in order: accepted, no gap, no reorder", "[bridge][replay]") {
  ReplayWindow<> window;
  CHECK_FALSE(window.started());
  for (std::uint64_t s = 0; s < 5000; ++s) {
    const auto r = window.accept(s);
    REQUIRE(r.accepted());
    REQUIRE_FALSE(r.reordered());
    REQUIRE(r.gap == 0);
  }
  CHECK(window.newest() == 4999);
}

TEST_CASE("the first number may be anything", "[bridge][replay]") {
  for (const std::uint64_t first : {std::uint64_t{0}, std::uint64_t{1} << 40, kMax}) {
    ReplayWindow<> window;
    const auto r = window.accept(first);
    CHECK(r.accepted());
    CHECK(r.gap == 0);
    CHECK(window.newest() == first);
    CHECK(window.accept(first).verdict == ReplayVerdict::duplicate);
  }
}

TEST_CASE("duplicates are refused, the newest and older ones", "[bridge][replay]") {
  ReplayWindow<> window;
  for (std::uint64_t s = 100; s <= 200; ++s) REQUIRE(window.accept(s).accepted());
  CHECK(window.accept(200).verdict == ReplayVerdict::duplicate);
  CHECK(window.accept(150).verdict == ReplayVerdict::duplicate);
  CHECK(window.accept(100).verdict == ReplayVerdict::duplicate);
  CHECK(window.accept(201).accepted());
  CHECK(window.accept(201).verdict == ReplayVerdict::duplicate);
}

TEST_CASE("a gap is counted, and its numbers are accepted late once", "[bridge][replay]") {
  ReplayWindow<> window;
  REQUIRE(window.accept(10).accepted());
  const auto jump = window.accept(15);
  CHECK(jump.accepted());
  CHECK(jump.gap == 4);
  CHECK_FALSE(jump.reordered());
  const auto late = window.accept(12);
  CHECK(late.accepted());
  CHECK(late.reordered_by == 3);
  CHECK(late.gap == 0);
  CHECK(window.accept(12).verdict == ReplayVerdict::duplicate);
  CHECK(window.accept(14).reordered_by == 1);
  CHECK(window.newest() == 15);
}

TEST_CASE("the window's edge: Width - 1 behind is accepted, Width behind is too old", "[bridge][replay]") {
  ReplayWindow<1024> window;
  REQUIRE(window.accept(5000).accepted());
  CHECK(window.accept(5000 - 1023).reordered_by == 1023);
  CHECK(window.accept(5000 - 1024).verdict == ReplayVerdict::too_old);
  CHECK(window.accept(0).verdict == ReplayVerdict::too_old);
  // At every alignment of the newest number to the 64-bit words.
  for (std::uint64_t newest = 3000; newest < 3200; ++newest) {
    ReplayWindow<1024> w;
    REQUIRE(w.accept(newest - 1023).accepted());
    REQUIRE(w.accept(newest).gap == 1022);
    CAPTURE(newest);
    REQUIRE(w.accept(newest - 1023).verdict == ReplayVerdict::duplicate);
    REQUIRE(w.accept(newest - 1022).reordered_by == 1022);
    REQUIRE(w.accept(newest - 1024).verdict == ReplayVerdict::too_old);
  }
}

TEST_CASE("far jumps forget the past and keep working", "[bridge][replay]") {
  ReplayWindow<> window;
  for (std::uint64_t s = 0; s < 100; ++s) REQUIRE(window.accept(s).accepted());
  const std::uint64_t far = std::uint64_t{1} << 50;
  CHECK(window.accept(far).gap == far - 100);
  CHECK(window.accept(99).verdict == ReplayVerdict::too_old);
  CHECK(window.accept(far - 1).reordered_by == 1);
  CHECK(window.accept(far).verdict == ReplayVerdict::duplicate);
  // Numbers that share word positions with the old ones are not mistaken for them.
  CHECK(window.accept(far + 64).gap == 63);
  CHECK(window.accept(far + 1).reordered_by == 63);

  // To the very top of the range.
  CHECK(window.accept(kMax - 1).gap == kMax - 1 - (far + 64) - 1);
  CHECK(window.accept(kMax).gap == 0);
  CHECK(window.accept(kMax).verdict == ReplayVerdict::duplicate);
  CHECK(window.accept(kMax - 1).verdict == ReplayVerdict::duplicate);
  CHECK(window.accept(kMax - 1023).reordered_by == 1023);
  CHECK(window.accept(kMax - 1024).verdict == ReplayVerdict::too_old);
  CHECK(window.accept(0).verdict == ReplayVerdict::too_old);
}

TEST_CASE("would_accept predicts without recording, and reset forgets", "[bridge][replay]") {
  ReplayWindow<> window;
  CHECK(window.would_accept(7));
  REQUIRE(window.accept(7).accepted());
  CHECK_FALSE(window.would_accept(7));
  CHECK(window.would_accept(6));
  CHECK(window.would_accept(6));
  CHECK(window.accept(6).accepted());
  window.reset();
  CHECK_FALSE(window.started());
  CHECK(window.accept(6).accepted());
  CHECK(window.accept(3).reordered_by == 3);
}

TEST_CASE("agrees with a complete record on random traffic", "[bridge][replay]") {
  check_against_reference<64>(1, 0);
  check_against_reference<128>(2, 1000);
  check_against_reference<1024>(3, 0);
  check_against_reference<1024>(4, std::uint64_t{1} << 62);
  check_against_reference<2048>(5, 12345);
}

TEST_CASE("the window is a fixed-size value", "[bridge][replay]") {
  STATIC_REQUIRE(sizeof(ReplayWindow<1024>) <= 17 * 8 + 16);
  STATIC_REQUIRE(std::is_trivially_copyable_v<ReplayWindow<1024>>);
}
