#include "sweep_table.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace lever::hil {

SweepTable::SweepTable(const std::string& run_keys, const std::string& summary_keys, std::vector<SweepColumn> columns)
    : columns_(std::move(columns)),
      spread_(columns_.size()),
      runs_(run_keys + ",seed"),
      summary_(summary_keys + ",seeds") {
  for (const auto& c : columns_) {
    if (c.run_name) runs_ += fmt::format(",{}", c.run_name);
    if (c.summary_name) summary_ += fmt::format(",{0},{0}_min,{0}_max", c.summary_name);
  }
  runs_ += "\n";
  summary_ += "\n";
}

void SweepTable::add_run(const std::string& keys, std::uint64_t seed, const std::vector<double>& values) {
  runs_ += fmt::format("{},{}", keys, seed);
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    if (columns_[k].run_name) runs_ += "," + fmt::format(fmt::runtime(columns_[k].run_format), values[k]);
    Spread& s = spread_[k];
    s.sum += values[k];
    s.min = std::min(s.min, values[k]);
    s.max = std::max(s.max, values[k]);
  }
  runs_ += "\n";
  ++seeds_;
}

void SweepTable::end_point(const std::string& keys) {
  summary_ += fmt::format("{},{}", keys, seeds_);
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    const SweepColumn& c = columns_[k];
    const Spread& s = spread_[k];
    if (c.summary_name)
      summary_ += fmt::format(",{:.{}f},{:.{}f},{:.{}f}", c.scale * s.sum / seeds_, c.digits, c.scale * s.min, c.digits,
                              c.scale * s.max, c.digits);
  }
  summary_ += "\n";
  spread_.assign(columns_.size(), Spread{});
  seeds_ = 0;
}

}  // namespace lever::hil
