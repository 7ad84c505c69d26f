// LatestValue: the newest value, and never a torn one while a writer publishes as fast as it can.
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <thread>

#include "lever/board/latest_value.hpp"

using lever::board::LatestValue;

namespace {

// Eight words that must always agree: a torn read mixes two publications and breaks the relation.
struct Stamped {
  std::uint64_t words[8] = {};
  static Stamped of(std::uint64_t n) {
    Stamped s;
    for (std::uint64_t i = 0; i < 8; ++i) s.words[i] = (n * (i + 1)) ^ (i << 56);
    return s;
  }
  bool consistent() const { return of(words[0]).words[7] == words[7] && of(words[0]).words[3] == words[3]; }
};

}  // namespace

TEST_CASE("LatestValue is empty before the first publish, then holds the newest value") {
  LatestValue<Stamped> latest;
  CHECK_FALSE(latest.load());
  latest.publish(Stamped::of(1));
  REQUIRE(latest.load());
  CHECK(latest.load()->words[0] == 1);
  latest.publish(Stamped::of(2));
  latest.publish(Stamped::of(3));
  CHECK(latest.load()->words[0] == 3);
  CHECK(latest.load()->consistent());
}

TEST_CASE("LatestValue never hands a reader a torn or older value while a writer races it") {
  // Two readers and a writer on a machine of two cores: the readers also get preempted between their steps,
  // which is where a wrong seqlock goes wrong.
  struct ReaderTally {
    std::uint64_t reads = 0;
    std::uint64_t torn = 0;
    std::uint64_t went_back = 0;
    std::uint64_t newest = 0;
  };
  LatestValue<Stamped> latest;
  std::atomic<bool> done{false};
  auto read_until_done = [&](ReaderTally& tally) {
    while (!done.load(std::memory_order_relaxed)) {
      const auto value = latest.load();
      if (!value) continue;
      ++tally.reads;
      if (!value->consistent()) ++tally.torn;
      if (value->words[0] < tally.newest) ++tally.went_back;
      tally.newest = value->words[0];
    }
  };
  ReaderTally first;
  ReaderTally second;
  {
    std::jthread writer([&] {
      for (std::uint64_t n = 1; !done.load(std::memory_order_relaxed); ++n) latest.publish(Stamped::of(n));
    });
    std::jthread reader([&] { read_until_done(second); });
    std::jthread stopper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(400));
      done = true;
    });
    read_until_done(first);
  }
  for (const ReaderTally* tally : {&first, &second}) {
    INFO("reads " << tally->reads << ", newest " << tally->newest);
    CHECK(tally->reads > 10'000);
    CHECK(tally->newest > 1'000);  // the writer really ran during the reads
    CHECK(tally->torn == 0);
    CHECK(tally->went_back == 0);
  }
}
