#include "bridge_stats.hpp"

#include <cmath>

namespace lever::bridge {
namespace {

constexpr double kBucketGrowth = 1.05;

std::size_t bucket_of(std::int64_t us) {
  if (us <= 1) return 0;
  const auto b = static_cast<std::size_t>(std::log(static_cast<double>(us)) / std::log(kBucketGrowth));
  return b;
}

}  // namespace

void LatencyHistogram::add(std::int64_t us) noexcept {
  if (us < 0) us = 0;  // clock offset estimates can be off by a few microseconds
  const std::size_t b = bucket_of(us);
  ++buckets_[b < kBuckets ? b : kBuckets - 1];
  ++count_;
  if (us > max_) max_ = us;
}

std::optional<double> LatencyHistogram::percentile(double q) const noexcept {
  if (count_ == 0) return std::nullopt;
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += buckets_[b];
    if (seen >= rank && buckets_[b] > 0) return std::pow(kBucketGrowth, static_cast<double>(b) + 0.5);
  }
  return static_cast<double>(max_);
}

}  // namespace lever::bridge
