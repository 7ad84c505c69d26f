#include "lever/study/three_ifc.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "config_json.hpp"

namespace lever::study {

void check(const ThreeIfcConfig& c) {
  detail::require(c.interval_s > 0.0 && c.interval_s <= 3600.0, "interval_s", "a duration in (0, 3600] s");
  detail::require(c.gap_s >= 0.0 && c.gap_s <= 600.0, "gap_s", "a duration in [0, 600] s");
  detail::require(c.max_p > 0.0 && c.max_p < 1.0, "max_p", "a fraction in (0, 1)");
  detail::require(c.start_p > 0.0 && c.start_p <= c.max_p, "start_p", "a fraction in (0, max_p]");
  detail::require(c.step > 0.0 && c.step < 1.0, "step", "a fraction in (0, 1)");
  detail::require(c.right_in_a_row >= 1 && c.right_in_a_row <= 100, "right_in_a_row", "a whole number in [1, 100]");
  detail::require(c.pass3_factor > 0.0 && c.pass3_factor <= 1.0, "pass3_factor", "a factor in (0, 1]");
  detail::require(c.max_trials_per_pass >= c.right_in_a_row && c.max_trials_per_pass <= 10000, "max_trials_per_pass",
                  "a whole number in [right_in_a_row, 10000]");
  detail::require(c.briefing_p >= 0.0 && c.briefing_p < 1.0, "briefing_p", "a fraction in [0, 1)");
}

nlohmann::json to_json(const ThreeIfcConfig& c) {
  return {{"interval_s", c.interval_s},
          {"gap_s", c.gap_s},
          {"start_p", c.start_p},
          {"step", c.step},
          {"max_p", c.max_p},
          {"right_in_a_row", c.right_in_a_row},
          {"pass3_factor", c.pass3_factor},
          {"max_trials_per_pass", c.max_trials_per_pass},
          {"direction", std::string(name(c.direction))},
          {"briefing_p", c.briefing_p}};
}

ThreeIfcConfig three_ifc_config_from_json(const nlohmann::json& j) {
  ThreeIfcConfig c;
  detail::read(j, "interval_s", c.interval_s);
  detail::read(j, "gap_s", c.gap_s);
  detail::read(j, "start_p", c.start_p);
  detail::read(j, "step", c.step);
  detail::read(j, "max_p", c.max_p);
  detail::read(j, "right_in_a_row", c.right_in_a_row);
  detail::read(j, "pass3_factor", c.pass3_factor);
  detail::read(j, "max_trials_per_pass", c.max_trials_per_pass);
  detail::read(j, "direction", c.direction);
  detail::read(j, "briefing_p", c.briefing_p);
  check(c);
  return c;
}

ThreeIfcStaircase::ThreeIfcStaircase(ThreeIfcConfig config, std::uint64_t seed)
    : config_(config), seed_(seed), rng_(seed) {
  check(config_);
  present();
}

const Trial& ThreeIfcStaircase::current() const {
  if (done()) throw std::logic_error("the 3IFC procedure is over: no trial to present");
  return current_;
}

void ThreeIfcStaircase::start_pass(int pass, double p) {
  stage_ = Stage::trials;
  pass_ = pass;
  trial_ = 0;
  p_ = p;
  right_run_ = 0;
}

void ThreeIfcStaircase::end_pass(bool reached) {
  results_.push_back({p_, reached, trial_});
  if (pass_ == 1)
    stage_ = Stage::briefing;
  else if (pass_ == 2)
    // The subject is not told: pass 3 starts from half of pass 2's result at once, no briefing.
    start_pass(3, config_.pass3_factor * p_);
  else
    stage_ = Stage::done;
}

void ThreeIfcStaircase::present() {
  Trial t;
  t.direction = config_.direction;
  switch (stage_) {
    case Stage::familiarization:
      t.kind = Kind::familiarization;
      t.direction = Direction::both;
      t.intervals = {interval_for(Direction::both, 0.0, 0.0)};  // 0 s: until the experimenter ends it
      break;
    case Stage::briefing:
      t.kind = Kind::briefing;
      t.p = config_.briefing_p;
      t.intervals = {interval_for(config_.direction, config_.briefing_p, 0.0)};
      break;
    case Stage::trials: {
      t.kind = Kind::three_ifc;
      t.pass = pass_;
      t.trial = trial_ + 1;
      t.p = p_;
      t.carrier = uniform_index(rng_, 3) + 1;
      for (int i = 1; i <= 3; ++i)
        t.intervals.push_back(interval_for(config_.direction, i == t.carrier ? p_ : 0.0, config_.interval_s));
      t.gap_s = config_.gap_s;
      t.answer_min = 1;
      t.answer_max = 3;
      break;
    }
    case Stage::done:
      break;
  }
  current_ = t;
}

Outcome ThreeIfcStaircase::answer(int n) {
  if (stage_ != Stage::trials) throw std::logic_error("this step takes an acknowledgement, not an answer");
  if (n < 1 || n > 3) return {false, std::nullopt, fmt::format("the answer is an interval, 1, 2 or 3, not {}", n)};
  const bool right = n == current_.carrier;
  ++trial_;
  if (right) {
    if (++right_run_ >= config_.right_in_a_row) {
      end_pass(true);
      present();
      return {true, true, {}};
    }
  } else {
    right_run_ = 0;
    p_ = std::min(p_ + config_.step, config_.max_p);
  }
  if (trial_ >= config_.max_trials_per_pass) end_pass(false);
  present();
  return {true, right, {}};
}

void ThreeIfcStaircase::acknowledge() {
  if (stage_ == Stage::familiarization)
    start_pass(1, config_.start_p);
  else if (stage_ == Stage::briefing)
    start_pass(2, config_.start_p);
  else
    throw std::logic_error(done() ? "the 3IFC procedure is over" : "a 3IFC trial takes an answer, 1, 2 or 3");
  present();
}

void ThreeIfcStaircase::void_trial() {
  if (done()) throw std::logic_error("the 3IFC procedure is over: no trial to void");
  present();  // a new carrier: a repeat tells the subject nothing about where p was
}

std::optional<double> ThreeIfcStaircase::threshold() const {
  if (results_.size() < 3) return std::nullopt;
  double sum = 0.0;
  for (const auto& r : results_) sum += r.p;
  return sum / static_cast<double>(results_.size());
}

bool ThreeIfcStaircase::reached() const {
  return results_.size() == 3 && std::all_of(results_.begin(), results_.end(), [](const auto& r) { return r.reached; });
}

}  // namespace lever::study
