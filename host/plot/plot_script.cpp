#include "plot_script.hpp"

#include <fmt/format.h>

#include <cmath>

namespace lever::plot {
namespace {

bool any_value(const Session& s, double TimelineRow::*column) {
  for (const auto& r : s.timeline)
    if (!std::isnan(r.*column)) return true;
  return false;
}

bool any_value(const Session& s, int TimelineRow::*column) {
  for (const auto& r : s.timeline)
    if (r.*column >= 0) return true;
  return false;
}

// plot SERIES...: one gnuplot plot command of the series given (each "file using ... title ..."), continued lines
std::string plot_command(const std::vector<std::string>& series) {
  std::string g = "plot ";
  for (std::size_t i = 0; i < series.size(); ++i) g += (i ? ", \\\n     " : "") + series[i];
  return g + "\n";
}

}  // namespace

PlotScript gnuplot_script(const Session& s, const std::string& title) {
  const bool log = s.source == "candump";
  // A log holds the force only at the frames the TOP sent (points); the HIL's trace every tick (a line). Likewise
  // the TOP's position: a log has it once a second from its status lines.
  const std::string samples = log ? "with points pt 7 ps 0.5" : "with lines";
  PlotScript p;
  std::string& g = p.text;
  g = fmt::format("# lever-plot: {} ({}); `gnuplot plots.gp` redraws the PNGs beside it.\n", title,
                  log ? "a candump -L recording" : "a lever-hil run trace");
  g += "dir = ARG0\n"
       "while (strlen(dir) > 0 && dir[strlen(dir):strlen(dir)] ne \"/\") { dir = dir[1:strlen(dir) - 1] }\n"
       "timeline = dir . \"timeline.csv\"\nrates = dir . \"rates.csv\"\n"
       "set datafile separator \",\"\nset datafile missing \"\"\n"
       "set key below horizontal\nset grid\nset xlabel \"time (s)\"\n";
  auto figure = [&](const std::string& png, const std::string& size) {
    g += fmt::format("set terminal pngcairo size {} font \",11\" noenhanced\nset output dir . \"{}\"\n", size, png);
    p.pngs.push_back(png);
  };
  const bool tracking = any_value(s, &TimelineRow::tracking_error);
  std::vector<std::string> positions;
  if (any_value(s, &TimelineRow::hsi_position))
    positions.push_back(fmt::format("timeline using \"t\":\"hsi_position\" with lines lw 2 title \"HSI{}\"",
                                    log ? " (as sent to the TOP)" : ""));
  else
    p.left_out.push_back("the HSI's position: no motion frames of the pair");
  if (any_value(s, &TimelineRow::top_position))
    positions.push_back(fmt::format("timeline using \"t\":\"top_position\" {} title \"TOP{}\"",
                                    log ? "with points pt 7 ps 1" : "with lines", log ? " (status lines)" : ""));
  else
    p.left_out.push_back(
        "the TOP's position and the tracking error: no TOP position (a recording has it from the TOP's status lines: "
        "--status)");
  if (!tracking && any_value(s, &TimelineRow::top_position))
    p.left_out.push_back("the tracking error: no time with both levers' positions");
  if (!positions.empty()) {
    figure("positions.png", tracking ? "900,600" : "900,450");
    if (tracking)
      g += fmt::format("set multiplot layout 2,1 title \"{}: lever positions\"\n", title);
    else
      g += fmt::format("set title \"{}: lever positions\"\n", title);
    g += "set ylabel \"position (rad)\"\n" + plot_command(positions);
    if (tracking) {
      g += "set ylabel \"tracking error (rad)\"\n";
      g += plot_command({fmt::format("timeline using \"t\":\"tracking_error\" {} lc 3 title \"HSI - TOP\"",
                                     log ? "with points pt 7 ps 1" : "with lines")});
      g += "unset multiplot\n";
    } else {
      g += "unset title\n";
    }
  }

  std::vector<std::string> force;
  if (any_value(s, &TimelineRow::measured_force))
    force.push_back(fmt::format("timeline using \"t\":\"measured_force\" {} title \"measured at the TOP{}\"", samples,
                                log ? " (the frames sent)" : ""));
  if (any_value(s, &TimelineRow::displayed_force))
    force.push_back("timeline using \"t\":\"displayed_force\" with lines lw 2 title \"displayed at the HSI\"");
  if (force.empty()) {
    p.left_out.push_back("the force: no force frames of the pair");
  } else {
    figure("force.png", "900,450");
    g += fmt::format("set title \"{}: force measured at the TOP and displayed at the HSI\"\n", title);
    g += "set ylabel \"force (N)\"\n" + plot_command(force);
  }

  if (s.rates.empty()) {
    p.left_out.push_back("the packet rate: no frames");
  } else {
    figure("packet_rate.png", "900,450");
    g += fmt::format("set title \"{}: data frames per second ({} s bins; 1000/s is every tick)\"\n", title, kRateBin);
    g += "set ylabel \"frames/s\"\nset yrange [0:*]\n";
    std::vector<std::string> rates = {"rates using \"t\":\"motion_per_s\" with steps lw 2 title \"motion HSI -> TOP\"",
                                      "rates using \"t\":\"force_per_s\" with steps lw 2 title \"force TOP -> HSI\""};
    if (log) {
      rates.push_back(
          "rates using \"t\":\"motion_deadband_per_s\" with steps dt 2 lc 1 title \"motion: by the deadband\"");
      rates.push_back(
          "rates using \"t\":\"force_deadband_per_s\" with steps dt 2 lc 2 title \"force: by the deadband\"");
    }
    g += plot_command(rates) + "set yrange [*:*]\n";
  }

  std::vector<std::string> states;
  if (any_value(s, &TimelineRow::hsi_state))
    states.push_back("timeline using \"t\":(column(\"hsi_state\") - 0.05) with steps lw 2 title \"HSI\"");
  if (any_value(s, &TimelineRow::top_state))
    states.push_back("timeline using \"t\":(column(\"top_state\") + 0.05) with steps lw 2 title \"TOP\"");
  if (log && any_value(s, &TimelineRow::hsi_faults))
    states.push_back(
        "timeline using \"t\":(column(\"hsi_faults\") > 0 ? 3 : 1/0) with points pt 2 lc 1 title \"HSI: a fault "
        "latched\"");
  if (log && any_value(s, &TimelineRow::top_faults))
    states.push_back(
        "timeline using \"t\":(column(\"top_faults\") > 0 ? 3.2 : 1/0) with points pt 2 lc 2 title \"TOP: a fault "
        "latched\"");
  if (states.empty()) {
    p.left_out.push_back("the states: no heartbeats of the pair");
  } else {
    figure("states.png", "900,450");
    g += fmt::format("set title \"{}: lever states{}\"\n", title, log ? " and latched faults" : "");
    g += "set ylabel \"state\"\nset yrange [-0.5:4.5]\n"
         "set ytics (\"init\" 0, \"disarmed\" 1, \"armed\" 2, \"fault\" 3, \"homing\" 4)\n";
    g += plot_command(states);
  }
  return p;
}

}  // namespace lever::plot
