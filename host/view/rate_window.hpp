#pragma once
// Events per second over the last whole second, counted in 100 ms buckets of the events' own time stamps: a log
// replayed gives the figures the live bus gave, and a bus gone silent reads 0 a second later.
#include <array>
#include <cstddef>
#include <cstdint>

namespace lever::view {

class RateWindow {
 public:
  static constexpr std::int64_t kBucketUs = 100'000;
  static constexpr std::size_t kBuckets = 10;  // one second

  // An event of `amount` at t_us. One stamped before the newest bucket (clocks are not strictly ordered across
  // threads) counts in the newest.
  void add(std::int64_t t_us, std::uint64_t amount = 1) noexcept;
  // The sum over the ten whole buckets before the one `now_us` falls in.
  std::uint64_t last_second(std::int64_t now_us) const noexcept;
  void reset() noexcept { *this = RateWindow{}; }

 private:
  static std::int64_t bucket_of(std::int64_t t_us) noexcept {
    return t_us >= 0 ? t_us / kBucketUs : -((-t_us + kBucketUs - 1) / kBucketUs);
  }
  // The window's buckets and the one filling now.
  static constexpr std::size_t kSlots = kBuckets + 1;
  static std::size_t slot(std::int64_t bucket) noexcept {
    const auto n = static_cast<std::int64_t>(kSlots);
    return static_cast<std::size_t>(((bucket % n) + n) % n);
  }

  std::array<std::uint64_t, kSlots> counts_{};
  std::int64_t newest_ = 0;
  bool started_ = false;
};

}  // namespace lever::view
