// LatestValue: the newest value, and never a torn one while a writer publishes as fast as it can.
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <thread>

#include "lever/linux/latest_value.hpp"

using lever::linux_io::LatestValue;

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
  LatestValue<Stamped> latest;
  std::atomic<bool> done{false};
  std::jthread writer([&] {
    for (std::uint64_t n = 1; !done.load(std::memory_order_relaxed); ++n) latest.publish(Stamped::of(n));
  });

  std::uint64_t reads = 0;
  std::uint64_t torn = 0;
  std::uint64_t went_back = 0;
  std::uint64_t newest = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  while (std::chrono::steady_clock::now() < until) {
    for (int i = 0; i < 1000; ++i) {
      const auto value = latest.load();
      if (!value) continue;
      ++reads;
      if (!value->consistent()) ++torn;
      if (value->words[0] < newest) ++went_back;
      newest = value->words[0];
    }
  }
  done = true;
  writer.join();
  INFO("reads " << reads << ", newest " << newest);
  CHECK(reads > 10'000);
  CHECK(newest > 1'000);  // the writer really ran during the reads
  CHECK(torn == 0);
  CHECK(went_back == 0);
}
