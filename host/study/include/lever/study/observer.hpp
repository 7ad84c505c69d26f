#pragma once
// Simulated observers: answers from models with a literature source (docs/study.md, "Simulated observers"). Their
// sessions are labelled simulated everywhere; they are not data.
#include <cstdint>
#include <optional>
#include <vector>

#include "lever/study/procedure.hpp"
#include "lever/study/three_ifc.hpp"

namespace lever::study {

// A Weibull psychometric function with guess and lapse rates (Wichmann and Hill 2001; Kingdom and Prins).
struct WeibullObserver {
  double threshold = 0.10;  // alpha
  double slope = 3.0;       // beta
  double lapse = 0.02;      // lambda
  double guess = 1.0 / 3.0;

  double p_right(double p) const;
  // The interval (1..3) the observer names for a 3IFC trial.
  int answer(const Trial& t, Rng& rng) const;
};

// Ratings linear in p, anchored on the paper's own text, with Gaussian noise, rounded and clipped to 1..10.
struct RatingObserver {
  double p1_velocity = 0.60;  // the p at which the mean rating reaches 1
  double p1_force = 0.15;
  double sigma = 1.0;

  double mean(Direction d, double p) const;
  int rate(const Trial& t, Rng& rng) const;
};

struct SimulatedThreeIfc {
  std::vector<PassResult> passes;
  std::optional<double> threshold;
  bool reached = false;
  int trials = 0;
};

// One whole simulated session; the procedure's and the observer's random numbers both come from `seed`.
SimulatedThreeIfc simulate_three_ifc(const ThreeIfcConfig& config, const WeibullObserver& observer, std::uint64_t seed);

struct Spread {
  int n = 0;
  double mean = 0.0, sd = 0.0, q1 = 0.0, median = 0.0, q3 = 0.0, min = 0.0, max = 0.0;
  double iqr() const { return q3 - q1; }
};
// Quartiles by linear interpolation between order statistics (Hyndman and Fan's type 7, R's and numpy's default).
Spread spread_of(std::vector<double> values);

}  // namespace lever::study
