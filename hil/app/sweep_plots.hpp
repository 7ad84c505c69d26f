#pragma once
// The gnuplot script every lever-hil sweep writes beside its summary.csv (plots.gp): figures of panels, each panel
// one or more summary metrics against the swept value, one curve per series (a variant), the mean over the seeds
// with bars from their min to their max. Columns are named, never numbered: the script reads summary.csv's header.
#include <string>
#include <vector>

namespace lever::hil {

struct PlotMetric {
  std::string column;  // summary.csv's metric (its _min and _max give the bars)
  std::string label;   // after the series' name in the legend; may be empty
};

struct PlotPanel {
  std::string title;   // may be empty
  std::string ylabel;  // may be empty: the one before stays
  std::string yrange;  // e.g. "[0:100]"; empty: the one before stays
  std::string
      filter;  // a gnuplot condition the rows must meet besides the series', e.g. strcol("direction") eq "force"
  std::vector<PlotMetric> metrics;
  std::string extra;  // more plot clauses after the curves (the paper's points), and their inline data after "\n"
};

struct PlotFigure {
  std::string output;  // the PNG's name
  std::string size;    // pngcairo's "width,height"
  std::string title;   // the figure's: over its panels, or the single panel's own
  std::vector<PlotPanel> panels;
};

struct PlotSpec {
  std::string what;                      // the script's first line says what it plots
  std::string x_column, xlabel, xrange;  // xrange may be empty: gnuplot fits it
  std::string series_column;
  std::vector<std::string> series;
  std::string preamble;  // more gnuplot lines before the figures (e.g. another data file's name)
  std::vector<PlotFigure> figures;
};

std::string gnuplot_script(const PlotSpec& spec);

}  // namespace lever::hil
