#include "sphere_clocks.hpp"

#include <cmath>

#include "lever/common/rng.hpp"

namespace lever::hil {
namespace {
constexpr Nanos kTickNs = 1'000'000;
}

SphereClocks::SphereClocks(const SphereConfig& c, const SphereDelays& delays)
    : own_(c.top_clock == SphereTopClock::own),
      delays_(delays),
      worst_delay_ns_(static_cast<Nanos>(std::ceil((c.network.delay_ms + c.network.jitter_ms) * 1e6))) {
  if (!own_) return;
  Rng rng(c.seed * 4 + 3);
  phase_ns_ = static_cast<Nanos>(std::floor(rng.uniform() * static_cast<double>(kTickNs)));
  drift_ = rng.uniform(-c.top_clock_drift_ppm_max, c.top_clock_drift_ppm_max) * 1e-6;
  period_ns_ = static_cast<double>(kTickNs) * (1.0 + drift_);
}

Nanos SphereClocks::top_tick_ns(std::uint64_t j) const {
  return phase_ns_ + static_cast<Nanos>(std::llround(static_cast<double>(j) * period_ns_));
}

double SphereClocks::top_clock_at(Nanos op_ns) const {
  return static_cast<double>(op_ns - phase_ns_) / period_ns_ * 1e-3;
}

std::optional<std::uint64_t> SphereClocks::top_tick_heard_by_op(std::uint64_t k) const {
  if (!own_) {
    const auto down = static_cast<std::uint64_t>(delays_.down_ticks);
    return k > down ? std::optional<std::uint64_t>(k - down) : std::nullopt;
  }
  // Strictly before the OP's tick: a TOP tick at the very nanosecond of the OP's runs after it (run_sphere).
  const Nanos by = static_cast<Nanos>(k) * kTickNs - worst_delay_ns_ - 1;
  if (by < phase_ns_) return std::nullopt;
  // The division's estimate, then the exact rule on the rounded tick times.
  auto j = static_cast<std::uint64_t>(static_cast<double>(by - phase_ns_) / period_ns_);
  while (top_tick_ns(j + 1) <= by) ++j;
  while (j > 0 && top_tick_ns(j) > by) --j;
  return j;
}

std::optional<std::uint64_t> SphereClocks::op_tick_heard_by_top(std::uint64_t j) const {
  if (!own_) {
    const auto up = static_cast<std::uint64_t>(delays_.up_ticks);
    return j > up ? std::optional<std::uint64_t>(j - up) : std::nullopt;
  }
  const Nanos by = top_tick_ns(j) - worst_delay_ns_;
  if (by < kTickNs) return std::nullopt;
  return static_cast<std::uint64_t>(by / kTickNs);
}

}  // namespace lever::hil
