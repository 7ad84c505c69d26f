#include "plot_script.hpp"

#include <fmt/format.h>

#include <filesystem>

namespace lever::plot {

std::string gnuplot_script(const Session& s, const std::string& title) {
  const bool log = s.source == "candump";
  // A log holds the force only at the frames the TOP sent (points); the HIL's trace every tick (a line). Likewise
  // the TOP's position: a log has it once a second from its status lines.
  const std::string samples = log ? "with points pt 7 ps 0.5" : "with lines";
  std::string g = fmt::format("# lever-plot: {} ({}); `gnuplot plots.gp` redraws the PNGs beside it.\n", title,
                              log ? "a candump -L recording" : "a lever-hil run trace");
  g += "dir = ARG0\n"
       "while (strlen(dir) > 0 && dir[strlen(dir):strlen(dir)] ne \"/\") { dir = dir[1:strlen(dir) - 1] }\n"
       "timeline = dir . \"timeline.csv\"\nrates = dir . \"rates.csv\"\n"
       "set datafile separator \",\"\nset datafile missing \"\"\n"
       "set key below horizontal\nset grid\nset xlabel \"time (s)\"\n";
  auto figure = [&](const std::string& png, const std::string& size) {
    g += fmt::format("set terminal pngcairo size {} font \",11\" noenhanced\nset output dir . \"{}\"\n", size, png);
  };
  figure("positions.png", "900,600");
  g += fmt::format("set multiplot layout 2,1 title \"{}: lever positions\"\n", title);
  g += "set ylabel \"position (rad)\"\n";
  g += fmt::format(
      "plot timeline using \"t\":\"hsi_position\" with lines lw 2 title \"HSI{}\", \\\n"
      "     timeline using \"t\":\"top_position\" {} title \"TOP{}\"\n",
      log ? " (as sent to the TOP)" : "", log ? "with points pt 7 ps 1" : "with lines", log ? " (status lines)" : "");
  g += "set ylabel \"tracking error (rad)\"\n";
  g += fmt::format("plot timeline using \"t\":\"tracking_error\" {} lc 3 title \"HSI - TOP\"\n",
                   log ? "with points pt 7 ps 1" : "with lines");
  g += "unset multiplot\n";

  figure("force.png", "900,450");
  g += fmt::format("set title \"{}: force measured at the TOP and displayed at the HSI\"\n", title);
  g += "set ylabel \"force (N)\"\n";
  g += fmt::format(
      "plot timeline using \"t\":\"measured_force\" {} title \"measured at the TOP{}\", \\\n"
      "     timeline using \"t\":\"displayed_force\" with lines lw 2 title \"displayed at the HSI\"\n",
      samples, log ? " (the frames sent)" : "");

  figure("packet_rate.png", "900,450");
  g += fmt::format("set title \"{}: data frames per second ({} s bins; 1000/s is every tick)\"\n", title, kRateBin);
  g += "set ylabel \"frames/s\"\nset yrange [0:*]\n";
  g += "plot rates using \"t\":\"motion_per_s\" with steps lw 2 title \"motion HSI -> TOP\", \\\n"
       "     rates using \"t\":\"force_per_s\" with steps lw 2 title \"force TOP -> HSI\"";
  if (log)
    g += ", \\\n     rates using \"t\":\"motion_deadband_per_s\" with steps dt 2 lc 1 title \"motion: by the "
         "deadband\", \\\n"
         "     rates using \"t\":\"force_deadband_per_s\" with steps dt 2 lc 2 title \"force: by the deadband\"";
  g += "\nset yrange [*:*]\n";

  figure("states.png", "900,450");
  g += fmt::format("set title \"{}: lever states{}\"\n", title, log ? " and latched faults" : "");
  g += "set ylabel \"state\"\nset yrange [-0.5:4.5]\n"
       "set ytics (\"init\" 0, \"disarmed\" 1, \"armed\" 2, \"fault\" 3, \"homing\" 4)\n";
  g += "plot timeline using \"t\":(column(\"hsi_state\") - 0.05) with steps lw 2 title \"HSI\", \\\n"
       "     timeline using \"t\":(column(\"top_state\") + 0.05) with steps lw 2 title \"TOP\"";
  if (log)
    g += ", \\\n     timeline using \"t\":(column(\"hsi_faults\") > 0 ? 3 : 1/0) with points pt 2 lc 1 "
         "title \"HSI: a fault latched\", \\\n"
         "     timeline using \"t\":(column(\"top_faults\") > 0 ? 3.2 : 1/0) with points pt 2 lc 2 "
         "title \"TOP: a fault latched\"";
  g += "\n";
  return g;
}

}  // namespace lever::plot
