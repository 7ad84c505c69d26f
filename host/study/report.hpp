#pragma once
// lever-study report: session logs summarised as the paper shows its studies, Fig. 7 (each subject's thresholds),
// Fig. 8 (each direction's traffic against p) and Fig. 11 (ratings against p), as text, CSV and PNG plots
// (docs/study.md, "lever-study").
#include <string>
#include <string_view>
#include <vector>

namespace lever::study {

enum class ReportTable { thresholds, traffic, ratings };
inline constexpr ReportTable kAllReportTables[] = {ReportTable::thresholds, ReportTable::traffic, ReportTable::ratings};
constexpr std::string_view name(ReportTable t) {
  return t == ReportTable::thresholds ? "thresholds" : t == ReportTable::traffic ? "traffic" : "ratings";
}

struct ReportOptions {
  std::vector<std::string> logs;
  bool csv = false;
  ReportTable table = ReportTable::thresholds;
  bool table_given = false;  // text: only that table; otherwise every table the logs fill
  std::string plots;         // a directory for the tables as CSV, plots.gp and its PNGs; "" none
};

// The exit status: 0, 1 (gnuplot failed or missing; the plots' directory could not be made), 2 (a log or the
// plots' directory refused).
int report(const ReportOptions& o);

}  // namespace lever::study
