#pragma once
// What a study procedure hands its runner: one trial at a time, what to present and what answer it takes. The
// procedures are pure state machines (no I/O, no clock): the runner presents, the procedure decides
// (docs/study.md).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lever/common/rng.hpp"

namespace lever::study {

// The paths a presentation's p is applied to (velocity: HSI to TOP, force: TOP to HSI).
enum class Direction { both, velocity, force };

enum class Kind {
  familiarization,  // presented and acknowledged; no answer counts
  briefing,         // 3IFC, before pass 2: the subject is told what the distortion feels like
  three_ifc,        // three intervals, the answer names the one that felt different (1..3)
  rating,           // one interval, rated 1..10
};

std::string_view name(Direction d);
std::string_view name(Kind k);
std::optional<Direction> direction_named(std::string_view s);
std::optional<Kind> kind_named(std::string_view s);

// One interval as the runner sets the pair up for it.
struct Interval {
  double p_velocity = 0.0;
  double p_force = 0.0;
  double duration_s = 0.0;
  bool operator==(const Interval&) const = default;
};

// An interval with p on the given paths and none on the other.
inline Interval interval_for(Direction d, double p, double duration_s) {
  return {d == Direction::force ? 0.0 : p, d == Direction::velocity ? 0.0 : p, duration_s};
}

struct Trial {
  Kind kind = Kind::familiarization;
  int pass = 0;   // 3IFC: pass 1..3; rating: run 1..; 0 for familiarization and briefing
  int trial = 0;  // the trial's number in its pass or run, from 1; 0 for familiarization and briefing
  double p = 0.0;
  Direction direction = Direction::both;
  int carrier = 0;  // 3IFC: the interval (1..3) that carries p; 0 otherwise
  std::vector<Interval> intervals;
  double gap_s = 0.0;  // between two intervals of one trial, for the runner to switch and confirm the settings
  int answer_min = 0;  // 0 and 0: the step takes an acknowledgement, not an answer
  int answer_max = 0;
  bool takes_answer() const { return answer_max > 0; }
};

struct Outcome {
  bool accepted = false;
  std::optional<bool> right;  // 3IFC: whether the answer named the carrier
  std::string refused;        // why an answer was refused (the state is unchanged)
};

// What both procedures offer the runner, so it runs either without knowing which.
class Procedure {
 public:
  virtual ~Procedure() = default;
  virtual std::string_view protocol() const = 0;  // "3ifc" or "rating", as in the log's header
  virtual nlohmann::json config_json() const = 0;
  virtual std::uint64_t seed() const = 0;
  virtual bool done() const = 0;
  // The trial to present now; precondition: !done().
  virtual const Trial& current() const = 0;
  // An answer to a trial that takes one: checked against the trial's range, then the procedure advances.
  virtual Outcome answer(int n) = 0;
  // Ends a familiarization or briefing step; throws std::logic_error on a trial that takes an answer.
  virtual void acknowledge() = 0;
  // The runner could not present the trial as meant (fault, disarm, settings not confirmed): the same trial again,
  // nothing else changes.
  virtual void void_trial() = 0;
};

// Uniform in [0, n), without the modulo's bias: draws above the largest multiple of n are drawn again.
inline int uniform_index(Rng& rng, int n) {
  const auto range = static_cast<std::uint64_t>(n);
  const std::uint64_t limit = UINT64_MAX - UINT64_MAX % range;
  std::uint64_t x = rng.next();
  while (x >= limit) x = rng.next();
  return static_cast<int>(x % range);
}

}  // namespace lever::study
