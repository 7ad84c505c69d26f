#include "lever/study/observer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lever::study {

double WeibullObserver::p_right(double p) const {
  if (p <= 0.0) return guess;
  return guess + (1.0 - guess - lapse) * (1.0 - std::exp(-std::pow(p / threshold, slope)));
}

int WeibullObserver::answer(const Trial& t, Rng& rng) const {
  if (t.kind != Kind::three_ifc) throw std::logic_error("a 3IFC observer answers 3IFC trials only");
  if (rng.uniform() < p_right(t.p)) return t.carrier;
  // Wrong: one of the two other intervals, either as likely.
  const int other = uniform_index(rng, 2);
  int seen = 0;
  for (int i = 1; i <= 3; ++i)
    if (i != t.carrier && seen++ == other) return i;
  return t.carrier == 1 ? 2 : 1;
}

double RatingObserver::mean(Direction d, double p) const {
  const double p1 = d == Direction::velocity ? p1_velocity
                    : d == Direction::force  ? p1_force
                                             : std::min(p1_velocity, p1_force);
  return 10.0 - 9.0 * p / p1;
}

int RatingObserver::rate(const Trial& t, Rng& rng) const {
  if (t.kind != Kind::rating) throw std::logic_error("a rating observer rates rating trials only");
  const double r = std::round(mean(t.direction, t.p) + sigma * rng.normal());
  return static_cast<int>(std::clamp(r, 1.0, 10.0));
}

SimulatedThreeIfc simulate_three_ifc(const ThreeIfcConfig& config, const WeibullObserver& observer,
                                     std::uint64_t seed) {
  // Two streams from one seed: the procedure's carrier draws must not depend on how the observer used its own.
  Rng seeder(seed);
  ThreeIfcStaircase staircase(config, seeder.next());
  Rng observer_rng(seeder.next());
  SimulatedThreeIfc out;
  while (!staircase.done()) {
    const Trial& t = staircase.current();
    if (!t.takes_answer()) {
      staircase.acknowledge();
      continue;
    }
    staircase.answer(observer.answer(t, observer_rng));
    ++out.trials;
  }
  out.passes = staircase.passes();
  out.threshold = staircase.threshold();
  out.reached = staircase.reached();
  return out;
}

Spread spread_of(std::vector<double> values) {
  Spread s;
  s.n = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const auto quantile = [&](double q) {
    const double h = q * static_cast<double>(values.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(h));
    const std::size_t hi = std::min(lo + 1, values.size() - 1);
    return values[lo] + (h - static_cast<double>(lo)) * (values[hi] - values[lo]);
  };
  double sum = 0.0;
  for (const double v : values) sum += v;
  s.mean = sum / static_cast<double>(values.size());
  double squares = 0.0;
  for (const double v : values) squares += (v - s.mean) * (v - s.mean);
  s.sd = values.size() > 1 ? std::sqrt(squares / static_cast<double>(values.size() - 1)) : 0.0;
  s.q1 = quantile(0.25);
  s.median = quantile(0.5);
  s.q3 = quantile(0.75);
  s.min = values.front();
  s.max = values.back();
  return s;
}

}  // namespace lever::study
