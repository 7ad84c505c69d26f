#pragma once
// Wake-up latencies in 1 µs bins, as cyclictest keeps them (a latency of 12.9 µs counts as 12), so that the
// loop's figures and cyclictest's are read the same way. Fixed size: recording allocates nothing.
#include <array>
#include <cstddef>
#include <cstdint>

namespace lever::board {

class LatencyHistogram {
 public:
  // 0 to 4999 µs; a later wake-up only counts as an overflow (and in max()). 5 ms is where the core latches
  // its TIMING fault at a 1 ms period.
  static constexpr std::size_t kBins = 5000;

  void record_ns(std::int64_t latency_ns) noexcept;  // a negative latency counts as 0
  // `count` latencies of `us` microseconds, from another tool's histogram.
  void add_us(std::uint64_t us, std::uint64_t count) noexcept;
  // Another histogram's latencies, as if recorded here (runs in rounds).
  void add(const LatencyHistogram& other) noexcept;
  // The exact worst latency when it is known apart from the bins (cyclictest reports it).
  void note_max_us(std::uint64_t us) noexcept;
  void clear() noexcept;

  std::uint64_t count() const noexcept { return count_; }
  std::uint64_t overflows() const noexcept { return overflows_; }
  std::uint64_t max_us() const noexcept { return max_ns_ / 1000; }
  // The smallest bin at or below which a fraction q of the latencies lie (the nearest-rank percentile);
  // max_us() when that rank is among the overflows; 0 when empty.
  std::uint64_t percentile_us(double q) const noexcept;

 private:
  std::array<std::uint64_t, kBins> bins_{};
  std::uint64_t overflows_ = 0;
  std::uint64_t count_ = 0;
  std::uint64_t max_ns_ = 0;
};

}  // namespace lever::board
