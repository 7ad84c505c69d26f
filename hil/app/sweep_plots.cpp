#include "sweep_plots.hpp"

#include <fmt/format.h>

#include "sweep_runner.hpp"

namespace lever::hil {
namespace {

// series(i): the i-th series' name, as a chain of conditionals (a name may hold spaces, so no word list).
std::string series_function(const std::vector<std::string>& series) {
  std::string f = "series(i) = ";
  for (std::size_t i = 0; i + 1 < series.size(); ++i) f += fmt::format("i == {} ? \"{}\" : ", i + 1, series[i]);
  return f + fmt::format("\"{}\"\n", series.empty() ? "" : series.back());
}

std::string curves(const PlotSpec& spec, const PlotPanel& panel) {
  std::string plot;
  for (std::size_t k = 0; k < panel.metrics.size(); ++k) {
    const PlotMetric& m = panel.metrics[k];
    const std::string row = fmt::format("strcol(\"{}\") eq series(i){}", spec.series_column,
                                        panel.filter.empty() ? "" : " && " + panel.filter);
    plot += fmt::format(
        "{}for [i=1:{}] file using \"{}\":(({}) ? column(\"{}\") : 1/0):\"{}_min\":\"{}_max\" with yerrorlines lc i "
        "dt {} title series(i){}",
        k == 0 ? "" : ", \\\n     ", spec.series.size(), spec.x_column, row, m.column, m.column, m.column, k + 1,
        m.label.empty() ? "" : fmt::format(" . \" {}\"", m.label));
  }
  return plot;
}

std::string panel_lines(const PlotSpec& spec, const PlotFigure& figure, const PlotPanel& panel) {
  std::string s;
  const std::string title = figure.panels.size() == 1 ? figure.title : panel.title;
  if (!title.empty()) s += fmt::format("set title \"{}\"\n", title);
  if (!panel.ylabel.empty()) s += fmt::format("set ylabel \"{}\"\n", panel.ylabel);
  if (!panel.yrange.empty()) s += fmt::format("set yrange {}\n", panel.yrange);
  const auto data = panel.extra.find('\n');
  s += "plot " + curves(spec, panel);
  if (!panel.extra.empty()) s += ", \\\n     " + panel.extra.substr(0, data);
  s += "\n";
  if (data != std::string::npos) s += panel.extra.substr(data + 1);
  return s;
}

}  // namespace

std::string gnuplot_script(const PlotSpec& spec) {
  std::string s =
      fmt::format("# {}: plots from summary.csv beside this script; `gnuplot plots.gp` redraws them.\n", spec.what);
  s += kGnuplotScriptDir;
  s += "file = dir . \"summary.csv\"\n";
  s += "set datafile separator \",\"\n";
  s += "set key below horizontal\nset grid\n";  // the legend below the plot, never over the curves
  s += fmt::format("set xlabel \"{}\"\n", spec.xlabel);
  if (!spec.xrange.empty()) s += fmt::format("set xrange {}\n", spec.xrange);
  s += series_function(spec.series) + spec.preamble;
  for (const PlotFigure& figure : spec.figures) {
    s += fmt::format("set terminal pngcairo size {} font \",11\" noenhanced\n", figure.size);
    s += fmt::format("set output dir . \"{}\"\n", figure.output);
    const bool multi = figure.panels.size() > 1;
    if (multi) s += fmt::format("set multiplot layout 1,{} title \"{}\"\n", figure.panels.size(), figure.title);
    for (const PlotPanel& panel : figure.panels) s += panel_lines(spec, figure, panel);
    if (multi) s += "unset multiplot\n";
  }
  return s;
}

}  // namespace lever::hil
