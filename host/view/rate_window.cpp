#include "rate_window.hpp"

namespace lever::view {

void RateWindow::add(std::int64_t t_us, std::uint64_t amount) noexcept {
  const std::int64_t bucket = bucket_of(t_us);
  if (!started_) {
    started_ = true;
    newest_ = bucket;
  } else if (bucket > newest_) {
    const std::int64_t steps = bucket - newest_;
    for (std::int64_t b = 1; b <= steps && b <= static_cast<std::int64_t>(kSlots); ++b) counts_[slot(newest_ + b)] = 0;
    newest_ = bucket;
  }
  counts_[slot(newest_)] += amount;
}

std::uint64_t RateWindow::last_second(std::int64_t now_us) const noexcept {
  if (!started_) return 0;
  const std::int64_t now = bucket_of(now_us);
  std::uint64_t sum = 0;
  for (std::int64_t k = 1; k <= static_cast<std::int64_t>(kBuckets); ++k) {
    const std::int64_t b = now - k;
    if (b > newest_ || b <= newest_ - static_cast<std::int64_t>(kSlots)) continue;  // not yet, or overwritten
    sum += counts_[slot(b)];
  }
  return sum;
}

}  // namespace lever::view
