#pragma once
// The gnuplot script lever-plot writes beside its CSV files (plots.gp), in lever-hil sweep's style: pngcairo,
// the legend below, a grid, columns by name, and no path in the script (it finds its data beside itself).
#include <string>
#include <vector>

#include "session.hpp"

namespace lever::plot {

struct PlotScript {
  std::string text;                   // plots.gp
  std::vector<std::string> pngs;      // the figures it draws, in order
  std::vector<std::string> left_out;  // "tracking error: no TOP position (...)": what the session cannot draw, and why
};

// Only the series the session has points for: gnuplot refuses a plot whose every series is empty ("x range is
// invalid"), and a plain candump -L recording has no TOP position (that comes from the TOP's status lines).
PlotScript gnuplot_script(const Session& s, const std::string& title);

}  // namespace lever::plot
