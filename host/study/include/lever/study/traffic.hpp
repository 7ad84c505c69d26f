#pragma once
// The paper's Fig. 8 from session logs: the data frames each direction sent during the study's intervals, as a
// share of the 1 kHz sample rate, against the p that direction ran at (docs/study.md, "lever-study", Fig. 8).
#include <map>
#include <vector>

#include "lever/study/session_log.hpp"

namespace lever::study {

// Samples a second on each path when every sample is sent: the levers' 1 kHz control rate.
inline constexpr double kSampleRateHz = 1000.0;

struct TrafficKey {
  Direction direction = Direction::velocity;  // velocity or force, never both
  double p = 0.0;                             // the p this direction ran at in the interval
  auto operator<=>(const TrafficKey&) const = default;
};

// What went into the table and what was left out, interval by interval.
struct TrafficTally {
  int counted = 0;      // intervals whose traffic is in the table
  int void_trial = 0;   // in a void trial's record: a fault, a disarm or a missed setting spoilt the trial
  int unconfirmed = 0;  // the levers' confirmation missing, or not the interval's p
  int unmeasured = 0;   // no bus times or frame counts (a simulated session's), or no time between start and end
};

class TrafficTable {
 public:
  // Each measured interval of the records' 3IFC and rating trials: two samples, one a direction, each in percent
  // of kSampleRateHz. Familiarization and briefing steps are left out, uncounted: the subject ends them when
  // ready and explores rather than operates as in a trial, so their traffic is not the study's.
  void add(const std::vector<TrialRecord>& records, bool simulated);

  const std::map<TrafficKey, std::vector<double>>& percent() const { return percent_; }
  // Whether a simulated session gave a sample to the point.
  bool simulated(const TrafficKey& key) const;
  const TrafficTally& tally() const { return tally_; }

 private:
  std::map<TrafficKey, std::vector<double>> percent_;
  std::map<TrafficKey, bool> simulated_;
  TrafficTally tally_;
};

// A direction's data frames in an interval as a share of the samples of its duration, in percent.
double traffic_percent(std::uint64_t frames, std::int64_t start_bus_us, std::int64_t end_bus_us);

}  // namespace lever::study
