#include "lever/board/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace lever::board {

void LatencyHistogram::record_ns(std::int64_t latency_ns) noexcept {
  const auto ns = static_cast<std::uint64_t>(std::max<std::int64_t>(latency_ns, 0));
  const std::uint64_t us = ns / 1000;
  if (us < kBins) {
    ++bins_[static_cast<std::size_t>(us)];  // us < kBins: fits a 32-bit size_t too
  } else {
    ++overflows_;
  }
  ++count_;
  max_ns_ = std::max(max_ns_, ns);
}

void LatencyHistogram::add_us(std::uint64_t us, std::uint64_t count) noexcept {
  if (count == 0) return;
  if (us < kBins) {
    bins_[static_cast<std::size_t>(us)] += count;
  } else {
    overflows_ += count;
  }
  count_ += count;
  max_ns_ = std::max(max_ns_, us * 1000);
}

void LatencyHistogram::add(const LatencyHistogram& other) noexcept {
  for (std::size_t us = 0; us < kBins; ++us) bins_[us] += other.bins_[us];
  overflows_ += other.overflows_;
  count_ += other.count_;
  max_ns_ = std::max(max_ns_, other.max_ns_);
}

void LatencyHistogram::note_max_us(std::uint64_t us) noexcept { max_ns_ = std::max(max_ns_, us * 1000); }

void LatencyHistogram::clear() noexcept { *this = LatencyHistogram{}; }

std::uint64_t LatencyHistogram::percentile_us(double q) const noexcept {
  if (count_ == 0) return 0;
  const double wanted = std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_));
  const std::uint64_t rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(wanted));
  std::uint64_t seen = 0;
  for (std::size_t us = 0; us < kBins; ++us) {
    seen += bins_[us];
    if (seen >= rank) return us;
  }
  return max_us();
}

}  // namespace lever::board
