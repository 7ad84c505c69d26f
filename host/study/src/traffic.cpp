#include "lever/study/traffic.hpp"

#include <cmath>

#include "lever/protocol/messages.hpp"

namespace lever::study {
namespace {

// p as the key of a point: sums of 0.025 steps differ in their last bits from session to session, one point all the
// same. A millionth is far below the settings frame's resolution (kPLsb).
double key_p(double p) { return std::round(p * 1e6) / 1e6; }

// What a lever's settings frame showed for the interval, against what the interval meant; a lever reports p in
// kPLsb steps, so anything within half a step is the same setting.
bool shows(const nlohmann::json& confirmed, const char* role, double p) {
  if (!confirmed.is_object() || !confirmed.contains(role)) return false;
  const auto& lever = confirmed.at(role);
  if (!lever.is_object() || !lever.contains("p") || !lever.at("p").is_number()) return false;
  return std::abs(lever.at("p").get<double>() - p) <= protocol::kPLsb / 2 + 1e-12;
}

}  // namespace

double traffic_percent(std::uint64_t frames, std::int64_t start_bus_us, std::int64_t end_bus_us) {
  const double seconds = static_cast<double>(end_bus_us - start_bus_us) / 1e6;
  return 100.0 * static_cast<double>(frames) / (seconds * kSampleRateHz);
}

void TrafficTable::add(const std::vector<TrialRecord>& records, bool simulated) {
  for (const auto& r : records) {
    if (r.kind != Kind::three_ifc && r.kind != Kind::rating) continue;
    for (const auto& i : r.intervals) {
      // A void trial's intervals before the one that spoilt it may look whole, but the trial was repeated: they are
      // not part of what the subject answered.
      if (r.void_reason) {
        ++tally_.void_trial;
        continue;
      }
      if (!i.start_bus_us || !i.end_bus_us || !i.frames_velocity || !i.frames_force ||
          *i.end_bus_us <= *i.start_bus_us) {
        ++tally_.unmeasured;
        continue;
      }
      // The HSI sends the velocity path, the TOP the force path.
      if (!shows(i.confirmed, "hsi", i.interval.p_velocity) || !shows(i.confirmed, "top", i.interval.p_force)) {
        ++tally_.unconfirmed;
        continue;
      }
      ++tally_.counted;
      const std::pair<TrafficKey, std::uint64_t> paths[] = {
          {{Direction::velocity, key_p(i.interval.p_velocity)}, *i.frames_velocity},
          {{Direction::force, key_p(i.interval.p_force)}, *i.frames_force}};
      for (const auto& [key, frames] : paths) {
        percent_[key].push_back(traffic_percent(frames, *i.start_bus_us, *i.end_bus_us));
        simulated_[key] = simulated_[key] || simulated;
      }
    }
  }
}

bool TrafficTable::simulated(const TrafficKey& key) const {
  const auto it = simulated_.find(key);
  return it != simulated_.end() && it->second;
}

}  // namespace lever::study
