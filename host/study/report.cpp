#include "report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

#include "lever/program/exit_codes.hpp"
#include "lever/program/gnuplot.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/text.hpp"
#include "lever/study/observer.hpp"
#include "lever/study/rating.hpp"
#include "lever/study/session_log.hpp"
#include "lever/study/three_ifc.hpp"
#include "lever/study/traffic.hpp"

namespace lever::study {
namespace {

namespace fs = std::filesystem;

struct SubjectThreshold {
  std::string log, subject;
  bool simulated = false;
  std::vector<PassResult> passes;
  std::optional<double> threshold;
  bool reached = false;
};

struct RatingCell {
  std::vector<double> ratings;
  bool simulated = false;
};

// Everything the logs say, read once for the text, the CSV and the plots alike.
struct Study {
  std::vector<SubjectThreshold> thresholds;
  std::map<std::pair<std::string, double>, RatingCell> ratings;  // (direction, p)
  TrafficTable traffic;
  int logs = 0, simulated_logs = 0;
  // One line for each log simulated on the HIL's pair: its traffic is the simulation's, on the simulation's clock.
  std::vector<std::string> on_simulator;
  bool any_simulated() const { return simulated_logs > 0; }
  bool all_simulated() const { return logs > 0 && simulated_logs == logs; }
};

Study read_logs(const std::vector<std::string>& paths) {
  Study st;
  for (const auto& path : paths) {
    const auto log = read_session_log(path);
    for (const auto& w : log.warnings) fmt::print(stderr, "lever-study: warning: {}\n", program::printable(w));
    ++st.logs;
    if (log.header.simulated) ++st.simulated_logs;
    if (const auto& sim = log.header.simulator; sim.is_object()) {
      const auto field = [&](const char* key) {
        if (!sim.contains(key)) return std::string("?");
        const auto& v = sim.at(key);
        return program::printable(v.is_string() ? v.get<std::string>() : v.dump());
      };
      st.on_simulator.push_back(fmt::format(
          "  {}: run on a simulated pair ({}: topology {}, gauge chain {}, seed {}); its bus times are the "
          "simulation's clock",
          program::printable(path), field("program"), field("topology"), field("gauge_chain"), field("seed")));
    }
    const auto procedure = resume(log);
    if (const auto* s = dynamic_cast<const ThreeIfcStaircase*>(procedure.get())) {
      st.thresholds.push_back(
          {path, log.header.subject, log.header.simulated, s->passes(), s->threshold(), s->reached()});
    } else if (const auto* r = dynamic_cast<const RatingRun*>(procedure.get())) {
      for (const auto& rating : r->ratings()) {
        auto& cell = st.ratings[{std::string(name(rating.direction)), rating.p}];
        cell.ratings.push_back(rating.rating);
        cell.simulated = cell.simulated || log.header.simulated;
      }
    }
    st.traffic.add(log.records, log.header.simulated);
  }
  return st;
}

// A CSV cell from a name or a path: no separator, quote or line break to split the row where gnuplot or a
// spreadsheet reads it.
std::string csv_cell(const std::string& text) {
  std::string cell = program::printable(text);
  std::replace_if(
      cell.begin(), cell.end(), [](char c) { return c == ',' || c == '"'; }, '_');
  return cell;
}

std::string thresholds_csv(const Study& st) {
  const auto pass_p = [](const SubjectThreshold& t, std::size_t i) {
    return i < t.passes.size() ? fmt::format("{}", t.passes[i].p) : std::string();
  };
  std::string csv = "log,subject,simulated,pass1,pass2,pass3,threshold,complete,reached\n";
  for (const auto& t : st.thresholds)
    csv += fmt::format("{},{},{},{},{},{},{},{},{}\n", csv_cell(t.log), csv_cell(t.subject), t.simulated, pass_p(t, 0),
                       pass_p(t, 1), pass_p(t, 2), t.threshold ? fmt::format("{}", *t.threshold) : "",
                       t.threshold.has_value(), t.reached);
  return csv;
}

std::string ratings_csv(const Study& st) {
  std::string csv = "direction,p,simulated,n,mean,sd,min,max\n";
  for (const auto& [key, cell] : st.ratings) {
    const auto s = spread_of(cell.ratings);
    csv += fmt::format("{},{},{},{},{},{},{},{}\n", key.first, key.second, cell.simulated, s.n, s.mean, s.sd, s.min,
                       s.max);
  }
  return csv;
}

std::string traffic_csv(const Study& st) {
  std::string csv = "direction,p,simulated,n,mean_percent,sd_percent,min_percent,max_percent\n";
  for (const auto& [key, percent] : st.traffic.percent()) {
    const auto s = spread_of(percent);
    csv += fmt::format("{},{},{},{},{},{},{},{}\n", name(key.direction), key.p, st.traffic.simulated(key), s.n, s.mean,
                       s.sd, s.min, s.max);
  }
  return csv;
}

void print_thresholds(const Study& st) {
  fmt::print("3IFC detection thresholds (Fig. 7)\n");
  if (st.thresholds.empty()) {
    fmt::print("  none: no 3IFC session among the logs\n");
    return;
  }
  fmt::print("{:<16} {:>8} {:>8} {:>8} {:>10}\n", "subject", "pass 1", "pass 2", "pass 3", "threshold");
  int complete = 0, above10 = 0, above11 = 0;
  for (const auto& t : st.thresholds) {
    const auto cell = [&](std::size_t i) {
      return i < t.passes.size() ? fmt::format("{:.2f}%{}", 100 * t.passes[i].p, t.passes[i].reached ? "" : "!")
                                 : std::string("-");
    };
    fmt::print("{:<16} {:>8} {:>8} {:>8} {:>10}\n", program::printable(t.subject) + (t.simulated ? " *" : ""), cell(0),
               cell(1), cell(2), t.threshold ? fmt::format("{:.2f}%", 100 * *t.threshold) : "incomplete");
    if (t.threshold) {
      ++complete;
      above10 += *t.threshold > 0.10 + 1e-9;
      above11 += *t.threshold > 0.11 + 1e-9;
    }
  }
  if (complete > 0)
    fmt::print("{} complete: above 10 %: {} ({:.0f} %), above 11 %: {} ({:.0f} %)\n", complete, above10,
               100.0 * above10 / complete, above11, 100.0 * above11 / complete);
  if (std::any_of(st.thresholds.begin(), st.thresholds.end(), [](const auto& t) {
        return std::any_of(t.passes.begin(), t.passes.end(), [](const auto& pass) { return !pass.reached; });
      }))
    fmt::print("! a pass that ended at its trial limit, not by three right answers in a row\n");
}

void print_traffic(const Study& st) {
  const auto& tally = st.traffic.tally();
  fmt::print("traffic against p (Fig. 8): data frames per direction, % of the 1 kHz samples, over the intervals\n");
  if (tally.counted == 0) {
    fmt::print("  none: no interval of a trial with bus times and frame counts{}\n",
               st.any_simulated() ? " (a simulated session has none: its intervals never ran on a pair)" : "");
  } else {
    fmt::print("{:<9} {:>7} {:>4} {:>7} {:>7} {:>7} {:>7}\n", "direction", "p", "n", "mean", "sd", "min", "max");
    for (const auto& [key, percent] : st.traffic.percent()) {
      const auto s = spread_of(percent);
      fmt::print("{:<9} {:>6.2f}% {:>4} {:>6.2f}% {:>6.2f}% {:>6.2f}% {:>6.2f}%{}\n", name(key.direction), 100 * key.p,
                 s.n, s.mean, s.sd, s.min, s.max, st.traffic.simulated(key) ? " *" : "");
    }
  }
  if (tally.void_trial + tally.unconfirmed + tally.unmeasured > 0)
    fmt::print(
        "{} intervals counted; left out: {} of void trials, {} not confirmed by both levers, {} without bus "
        "times or frame counts\n",
        tally.counted, tally.void_trial, tally.unconfirmed, tally.unmeasured);
}

void print_ratings(const Study& st) {
  fmt::print("ratings against p (Fig. 11)\n");
  if (st.ratings.empty()) {
    fmt::print("  none: no rating session among the logs\n");
    return;
  }
  fmt::print("{:<9} {:>7} {:>4} {:>6} {:>6}\n", "direction", "p", "n", "mean", "sd");
  for (const auto& [key, cell] : st.ratings) {
    const auto s = spread_of(cell.ratings);
    fmt::print("{:<9} {:>6.1f}% {:>4} {:>6.2f} {:>6.2f}{}\n", key.first, 100 * key.second, s.n, s.mean, s.sd,
               cell.simulated ? " *" : "");
  }
}

// The plots' files, each checked before anything is printed or written (a device, a link or a directory where a
// file goes is refused), the directory made if missing.
constexpr const char* kPlotFiles[] = {"thresholds.csv", "traffic.csv", "ratings.csv", "plots.gp",
                                      "fig7.png",       "fig8.png",    "fig11.png"};

void prepare_plots_dir(const std::string& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw program::BadInput(fmt::format("--plots {} exists and is not a directory", program::printable(dir)));
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", program::printable(dir), ec.message()));
  for (const char* file : kPlotFiles) program::OutputFile((fs::path(dir) / file).string(), "--plots");
}

// In the project's plot style (lever-hil's sweeps, lever-plot): the data beside the script, found through
// gnuplot's ARG0 so the directory's name is never gnuplot code, the legend below, a grid.
std::string plot_script(const Study& st) {
  const std::string simulated =
      st.all_simulated() ? "SIMULATED sessions, not data: " : (st.any_simulated() ? "(some sessions SIMULATED) " : "");
  std::string g =
      "# lever-study report: Fig. 7, 8 and 11 from session logs; `gnuplot plots.gp` redraws the PNGs beside it.\n"
      "dir = ARG0\n"
      "while (strlen(dir) > 0 && dir[strlen(dir):strlen(dir)] ne \"/\") { dir = dir[1:strlen(dir) - 1] }\n";
  const auto figure = [&](const char* png, const char* size, const std::string& title) {
    g += fmt::format(
        "reset\nset datafile separator \",\"\nset key below horizontal\nset grid\n"
        "set terminal pngcairo size {} font \",11\" noenhanced\nset output dir . \"{}\"\nset title \"{}{}\"\n",
        size, png, simulated, title);
  };
  if (!st.thresholds.empty()) {
    figure("fig7.png", "900,500", "3IFC detection threshold per subject (Fig. 7): each pass's p and their mean");
    // One subject a column, named below it; a fixed range, as one subject alone would give autoscale none.
    g += fmt::format("set xrange [-0.5:{}]\n", static_cast<double>(st.thresholds.size()) - 0.5);
    g += "file = dir . \"thresholds.csv\"\n"
         "set ylabel \"p (%)\"\nset yrange [0:*]\nset xtics rotate by -30\n"
         "plot file using 0:(100 * column(\"pass1\")):xtic(strcol(\"subject\")) with points pt 4 ps 1.5 "
         "title \"pass 1\", \\\n"
         "     file using 0:(100 * column(\"pass2\")) with points pt 6 ps 1.5 title \"pass 2\", \\\n"
         "     file using 0:(100 * column(\"pass3\")) with points pt 8 ps 1.5 title \"pass 3\", \\\n"
         "     file using 0:(100 * column(\"threshold\")) with points pt 7 ps 2 lc rgb \"black\" "
         "title \"threshold (mean of the passes)\", \\\n"
         "     10 with lines dt 2 lc rgb \"gray40\" title \"10 %\", \\\n"
         "     11 with lines dt 3 lc rgb \"gray20\" title \"11 %\"\n";
  }
  const auto against_p = [&](const char* file, const char* mean, const char* sd) {
    std::string plot = "plot ";
    const std::pair<const char*, const char*> series[] = {{"velocity", "velocity (HSI -> TOP)"},
                                                          {"force", "force (TOP -> HSI)"}};
    for (std::size_t i = 0; i < 2; ++i)
      plot += fmt::format(
          "{}dir . \"{}\" using (strcol(\"direction\") eq \"{}\" ? 100 * column(\"p\") : 1/0):\"{}\":\"{}\" "
          "with yerrorlines lw 2 pt {} title \"{}\"",
          i == 0 ? "" : ", \\\n     ", file, series[i].first, mean, sd, i == 0 ? 7 : 5, series[i].second);
    return plot + "\n";
  };
  if (!st.traffic.percent().empty()) {
    figure("fig8.png", "900,500", "data frames per direction against p (Fig. 8): mean +- sd over the intervals");
    g += "set xlabel \"p (%)\"\nset ylabel \"data frames (% of the 1 kHz samples)\"\nset yrange [0:*]\n"
         "set offsets 1, 1, 0, 0\n";
    g += against_p("traffic.csv", "mean_percent", "sd_percent");
  }
  if (!st.ratings.empty()) {
    figure("fig11.png", "900,500", "ratings against p (Fig. 11): mean +- sd");
    g += "set xlabel \"p (%)\"\nset ylabel \"rating (1 to 10)\"\n"
         "set yrange [0:11]\nset offsets 1, 1, 0, 0\n";
    g += against_p("ratings.csv", "mean", "sd");
  }
  return g;
}

int draw(const Study& st, const std::string& dir, bool csv) {
  const fs::path d(dir);
  program::OutputFile::write_all((d / "thresholds.csv").string(), thresholds_csv(st), "--plots");
  program::OutputFile::write_all((d / "traffic.csv").string(), traffic_csv(st), "--plots");
  program::OutputFile::write_all((d / "ratings.csv").string(), ratings_csv(st), "--plots");
  program::OutputFile::write_all((d / "plots.gp").string(), plot_script(st), "--plots");
  const int status = program::run_gnuplot(d / "plots.gp");
  if (status != 0) {
    fmt::print(stderr,
               "lever-study: gnuplot {}; the CSV files and plots.gp are in {} (install gnuplot-nox for plots)\n",
               status == 127 ? "could not be started" : fmt::format("failed (exit status {})", status),
               program::printable(dir));
    return program::kRuntimeFailure;
  }
  std::string drawn;
  const auto add = [&](bool has, const char* png) {
    // Whole paths, for a script to read the line; only their control bytes escaped.
    if (has) drawn += fmt::format(" {}", program::printable((d / png).string(), 4096));
  };
  add(!st.thresholds.empty(), "fig7.png");
  add(!st.traffic.percent().empty(), "fig8.png");
  add(!st.ratings.empty(), "fig11.png");
  // CSV on stdout stays CSV alone.
  std::FILE* to = csv ? stderr : stdout;
  fmt::print(to, "plots:{}\n", drawn.empty() ? " none (the logs hold no trial that counts)" : drawn);
  return program::kSuccess;
}

}  // namespace

int report(const ReportOptions& o) {
  try {
    const Study st = read_logs(o.logs);
    if (!o.plots.empty()) prepare_plots_dir(o.plots);
    if (o.csv) {
      fmt::print("{}", o.table == ReportTable::thresholds ? thresholds_csv(st)
                       : o.table == ReportTable::traffic  ? traffic_csv(st)
                                                          : ratings_csv(st));
    } else {
      if (st.any_simulated()) fmt::print("SIMULATED sessions among these logs (marked *): they are not data\n");
      for (const auto& line : st.on_simulator) fmt::print("{}\n", line);
      const auto wanted = [&](ReportTable t) { return !o.table_given || o.table == t; };
      const auto& tally = st.traffic.tally();
      // Without --table, a table is shown when the logs have something for it.
      if (wanted(ReportTable::thresholds) && (o.table_given || !st.thresholds.empty())) print_thresholds(st);
      if (wanted(ReportTable::traffic) &&
          (o.table_given || tally.counted + tally.void_trial + tally.unconfirmed + tally.unmeasured > 0))
        print_traffic(st);
      if (wanted(ReportTable::ratings) && (o.table_given || !st.ratings.empty())) print_ratings(st);
    }
    std::fflush(stdout);
    return o.plots.empty() ? program::kSuccess : draw(st, o.plots, o.csv);
  } catch (const SessionLogError& e) {
    fmt::print(stderr, "lever-study: {}\n", program::printable(e.what()));
    return program::kBadInput;
  } catch (const program::BadInput& e) {
    // Messages made here and by OutputFile, whose user text is already cut and escaped.
    fmt::print(stderr, "lever-study: {}\n", e.what());
    return program::kBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "lever-study: {}\n", e.what());
    return program::kRuntimeFailure;
  }
}

}  // namespace lever::study
