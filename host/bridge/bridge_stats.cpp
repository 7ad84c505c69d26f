#include "bridge_stats.hpp"

#include <cmath>

namespace lever::bridge {
namespace {

constexpr double kBucketGrowth = 1.05;

}  // namespace

std::size_t LatencyHistogram::bucket_of(std::int64_t us) noexcept {
  if (us <= 1) return 0;
  const auto b = static_cast<std::size_t>(std::log(static_cast<double>(us)) / std::log(kBucketGrowth));
  return b < kBuckets ? b : kBuckets - 1;
}

void LatencyHistogram::add(std::int64_t us) noexcept {
  if (us < 0) us = 0;  // clock offset estimates can be off by a few microseconds
  add_to_bucket(bucket_of(us), 1);
  note_max(us);
}

void LatencyHistogram::add_to_bucket(std::size_t bucket, std::uint64_t n) noexcept {
  buckets_[bucket < kBuckets ? bucket : kBuckets - 1] += n;
  count_ += n;
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

void SharedLatencyHistogram::add(std::int64_t us) noexcept {
  if (us < 0) us = 0;
  auto& total = totals_[LatencyHistogram::bucket_of(us)];
  total.store(total.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  std::int64_t seen = max_.load(std::memory_order_relaxed);
  while (us > seen && !max_.compare_exchange_weak(seen, us, std::memory_order_relaxed)) {
  }
}

LatencyHistogram SharedLatencyHistogram::take_interval() noexcept {
  LatencyHistogram interval;
  for (std::size_t b = 0; b < LatencyHistogram::kBuckets; ++b) {
    const std::uint64_t total = totals_[b].load(std::memory_order_relaxed);
    if (total != taken_[b]) interval.add_to_bucket(b, total - taken_[b]);
    taken_[b] = total;
  }
  interval.note_max(max_.exchange(0, std::memory_order_relaxed));
  return interval;
}

}  // namespace lever::bridge
