#include "lever/study/rating.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <utility>

#include "config_json.hpp"

namespace lever::study {

void check(const RatingConfig& c) {
  detail::require(c.interval_s > 0.0 && c.interval_s <= 3600.0, "interval_s", "a duration in (0, 3600] s");
  detail::require(!c.values.empty() && c.values.size() <= 100, "values", "a list of 1 to 100 values of p");
  for (const double p : c.values) detail::require(p >= 0.0 && p < 1.0, "values", "fractions in [0, 1)");
  detail::require(!c.runs.empty() && c.runs.size() <= 10, "runs", "a list of 1 to 10 directions");
  detail::require(c.heavy_p >= 0.0 && c.heavy_p < 1.0, "heavy_p", "a fraction in [0, 1)");
}

nlohmann::json to_json(const RatingConfig& c) {
  nlohmann::json runs = nlohmann::json::array();
  for (const auto d : c.runs) runs.push_back(std::string(name(d)));
  return {{"interval_s", c.interval_s}, {"values", c.values}, {"runs", runs}, {"heavy_p", c.heavy_p}};
}

RatingConfig rating_config_from_json(const nlohmann::json& j) {
  RatingConfig c;
  detail::read(j, "interval_s", c.interval_s);
  detail::read(j, "values", c.values);
  std::vector<std::string> runs;
  detail::read(j, "runs", runs);
  if (j.contains("runs")) {
    c.runs.clear();
    for (const auto& text : runs) {
      const auto d = direction_named(text);
      if (!d) throw std::invalid_argument(fmt::format("runs must name both, velocity or force, not '{}'", text));
      c.runs.push_back(*d);
    }
  }
  detail::read(j, "heavy_p", c.heavy_p);
  check(c);
  return c;
}

RatingRun::RatingRun(RatingConfig config, std::uint64_t seed) : config_(std::move(config)), seed_(seed) {
  check(config_);
  // Every order is drawn now, from the seed alone: a void trial or a resume cannot change what comes next.
  Rng rng(seed);
  for (std::size_t r = 0; r < config_.runs.size(); ++r) {
    auto order = config_.values;
    for (std::size_t i = order.size(); i > 1; --i)
      std::swap(order[i - 1], order[static_cast<std::size_t>(uniform_index(rng, static_cast<int>(i)))]);
    orders_.push_back(std::move(order));
  }
  present();
}

bool RatingRun::done() const { return familiarization_step_ >= 2 && run_ >= config_.runs.size(); }

const Trial& RatingRun::current() const {
  if (done()) throw std::logic_error("the rating procedure is over: no trial to present");
  return current_;
}

void RatingRun::present() {
  Trial t;
  if (familiarization_step_ < 2) {
    // First the undistorted system, then the heavily distorted example: the two ends of the rating scale.
    t.kind = Kind::familiarization;
    t.direction = Direction::both;
    t.p = familiarization_step_ == 0 ? 0.0 : config_.heavy_p;
    t.intervals = {interval_for(Direction::both, t.p, 0.0)};
  } else if (!done()) {
    t.kind = Kind::rating;
    t.pass = static_cast<int>(run_) + 1;
    t.trial = static_cast<int>(index_) + 1;
    t.p = orders_[run_][index_];
    t.direction = config_.runs[run_];
    t.intervals = {interval_for(t.direction, t.p, config_.interval_s)};
    t.answer_min = kRatingMin;
    t.answer_max = kRatingMax;
  }
  current_ = t;
}

Outcome RatingRun::answer(int n) {
  if (done() || familiarization_step_ < 2)
    throw std::logic_error(done() ? "the rating procedure is over" : "a familiarization step takes no rating");
  if (n < kRatingMin || n > kRatingMax)
    return {false, std::nullopt, fmt::format("a rating is a whole number from 1 to 10, not {}", n)};
  ratings_.push_back({current_.pass, current_.direction, current_.p, n});
  if (++index_ >= orders_[run_].size()) {
    ++run_;
    index_ = 0;
  }
  present();
  return {true, std::nullopt, {}};
}

void RatingRun::acknowledge() {
  if (familiarization_step_ >= 2)
    throw std::logic_error(done() ? "the rating procedure is over" : "a rating interval takes a rating, 1 to 10");
  ++familiarization_step_;
  present();
}

void RatingRun::void_trial() {
  if (done()) throw std::logic_error("the rating procedure is over: no trial to void");
  present();
}

}  // namespace lever::study
