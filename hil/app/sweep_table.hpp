#pragma once
// The CSV files every lever-hil sweep writes, with named columns: sweep.csv, one row a run (the point's keys, the
// seed, each metric in the run's units), and summary.csv, one row a point (its keys, the number of seeds, then each
// metric's mean, min and max over the seeds, in the summary's units: `name`, `name_min`, `name_max`).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace lever::hil {

// How one metric is written.
struct SweepColumn {
  const char* run_name;      // sweep.csv's column; nullptr: not in it
  const char* run_format;    // fmt format of the run's value, e.g. "{:.6f}"
  const char* summary_name;  // summary.csv's columns; nullptr: not in it
  double scale;              // summary units per run unit
  int digits;                // decimals in summary.csv
};

// A metric of one kind of run: its columns and its value (in the run's units).
template <typename Result>
struct SweepMetric {
  SweepColumn column;
  double (*value)(const Result&);
};

class SweepTable {
 public:
  // The key columns of a run (e.g. "variant,p") and of a point (e.g. "variant,p_percent"); the seed, the seeds and
  // the metrics' columns follow them.
  SweepTable(const std::string& run_keys, const std::string& summary_keys, std::vector<SweepColumn> columns);

  // One run of the current point: its key cells (e.g. "deadband,0.1"), its seed, one value per column.
  void add_run(const std::string& keys, std::uint64_t seed, const std::vector<double>& values);
  // Ends the point whose runs were added since the last end: its summary row.
  void end_point(const std::string& keys);

  const std::string& runs_csv() const { return runs_; }
  const std::string& summary_csv() const { return summary_; }

 private:
  struct Spread {
    double sum = 0, min = std::numeric_limits<double>::infinity(), max = -std::numeric_limits<double>::infinity();
  };
  std::vector<SweepColumn> columns_;
  std::vector<Spread> spread_;
  int seeds_ = 0;
  std::string runs_, summary_;
};

// Every metric's value for one run, in the order of `metrics`.
template <typename Result, std::size_t N>
std::vector<double> sweep_values(const SweepMetric<Result> (&metrics)[N], const Result& r) {
  std::vector<double> v;
  for (const auto& m : metrics) v.push_back(m.value(r));
  return v;
}
template <typename Result, std::size_t N>
std::vector<SweepColumn> sweep_columns(const SweepMetric<Result> (&metrics)[N]) {
  std::vector<SweepColumn> c;
  for (const auto& m : metrics) c.push_back(m.column);
  return c;
}

}  // namespace lever::hil
