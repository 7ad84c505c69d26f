#pragma once
// The paper's rating procedure (IV-B-3): familiarization, then one run per direction of twelve intervals with p in
// an order drawn from the seed, each rated 1..10 (docs/study.md).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "lever/study/procedure.hpp"

namespace lever::study {

struct RatingConfig {
  double interval_s = 30.0;
  std::vector<double> values{0.0, 0.025, 0.05, 0.075, 0.10, 0.125, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40};
  std::vector<Direction> runs{Direction::velocity, Direction::force};
  double heavy_p = 0.40;  // the heavily distorted example of the familiarization, on both directions
};

inline constexpr int kRatingMin = 1;
inline constexpr int kRatingMax = 10;

void check(const RatingConfig& c);
nlohmann::json to_json(const RatingConfig& c);
RatingConfig rating_config_from_json(const nlohmann::json& j);

struct Rating {
  int run = 0;
  Direction direction = Direction::velocity;
  double p = 0.0;
  int rating = 0;
};

class RatingRun final : public Procedure {
 public:
  RatingRun(RatingConfig config, std::uint64_t seed);

  std::string_view protocol() const override { return "rating"; }
  nlohmann::json config_json() const override { return to_json(config_); }
  std::uint64_t seed() const override { return seed_; }
  bool done() const override;
  const Trial& current() const override;
  Outcome answer(int n) override;
  void acknowledge() override;
  void void_trial() override;

  const RatingConfig& config() const { return config_; }
  // The order of p in each run, drawn at construction.
  const std::vector<std::vector<double>>& orders() const { return orders_; }
  const std::vector<Rating>& ratings() const { return ratings_; }

 private:
  void present();

  RatingConfig config_;
  std::uint64_t seed_;
  std::vector<std::vector<double>> orders_;
  int familiarization_step_ = 0;  // 0: undistorted, 1: heavily distorted, 2: over
  std::size_t run_ = 0;
  std::size_t index_ = 0;
  std::vector<Rating> ratings_;
  Trial current_;
};

}  // namespace lever::study
