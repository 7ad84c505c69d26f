#pragma once
// The paper's detection-threshold procedure (IV-A-2): a 3IFC staircase in three passes. Every rule and the
// readings where the paper is silent: docs/study.md.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "lever/study/procedure.hpp"

namespace lever::study {

struct ThreeIfcConfig {
  double interval_s = 20.0;
  double gap_s = 1.0;
  double start_p = 0.025;
  double step = 0.025;
  double max_p = 0.25;
  int right_in_a_row = 3;
  double pass3_factor = 0.5;
  // Not the paper's: a pass that never stops (a subject who cannot tell even max_p) ends here, not reached.
  int max_trials_per_pass = 60;
  Direction direction = Direction::both;
  double briefing_p = 0.25;
};

// Throws std::invalid_argument naming the field that is out of range.
void check(const ThreeIfcConfig& c);
nlohmann::json to_json(const ThreeIfcConfig& c);
// Missing fields keep their defaults; a wrong type or range throws.
ThreeIfcConfig three_ifc_config_from_json(const nlohmann::json& j);

struct PassResult {
  double p = 0.0;       // the p at which the right answers in a row occurred (or the pass ended)
  bool reached = true;  // false: the pass ended at max_trials_per_pass
  int trials = 0;       // answered trials in the pass, void ones not counted
};

class ThreeIfcStaircase final : public Procedure {
 public:
  ThreeIfcStaircase(ThreeIfcConfig config, std::uint64_t seed);

  std::string_view protocol() const override { return "3ifc"; }
  nlohmann::json config_json() const override { return to_json(config_); }
  std::uint64_t seed() const override { return seed_; }
  bool done() const override { return stage_ == Stage::done; }
  const Trial& current() const override;
  Outcome answer(int n) override;
  void acknowledge() override;
  void void_trial() override;

  const ThreeIfcConfig& config() const { return config_; }
  const std::vector<PassResult>& passes() const { return results_; }
  // The mean of the three passes' results, once all three ended; nullopt before.
  std::optional<double> threshold() const;
  // Whether every pass stopped by the rule (not by max_trials_per_pass).
  bool reached() const;
  int right_in_a_row() const { return right_run_; }

 private:
  enum class Stage { familiarization, trials, briefing, done };
  void start_pass(int pass, double p);
  void end_pass(bool reached);
  void present();

  ThreeIfcConfig config_;
  std::uint64_t seed_;
  Rng rng_;
  Stage stage_ = Stage::familiarization;
  int pass_ = 0;
  int trial_ = 0;
  double p_ = 0.0;
  int right_run_ = 0;
  std::vector<PassResult> results_;
  Trial current_;
};

}  // namespace lever::study
