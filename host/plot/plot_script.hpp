#pragma once
// The gnuplot script lever-plot writes beside its CSV files (plots.gp), in lever-hil sweep's style: pngcairo,
// the legend below, a grid, columns by name, and no path in the script (it finds its data beside itself).
#include <string>

#include "session.hpp"

namespace lever::plot {

std::string gnuplot_script(const Session& s, const std::string& title);

}  // namespace lever::plot
