#pragma once
#include <filesystem>
#include <initializer_list>
#include <string>

#include "lever/hil/human_operator.hpp"

namespace lever::hil {

struct SweepOptions {
  ScenarioKind scenario = ScenarioKind::wall_tap;
  std::string out_dir;
  int seeds = 3;
  double duration_s = 20.0;
  int jobs = 2;
  double floor_velocity = 0.02;
  double floor_force = 0.05;
  // The prefilter's cut-off per direction, for the filter variants; each beyond the perception range of its
  // modality (the paper's III-E): kinesthetic sensing of motion reaches about 20-30 Hz, so velocity is filtered
  // at 30 Hz; force is felt as vibration up to about 1 kHz (Pacinian corpuscles, most sensitive near 250 Hz),
  // beyond the loop's 500 Hz Nyquist, so any cut-off the 1 kHz loop can have removes what can be felt: off.
  double filter_hz_velocity = 30.0;
  double filter_hz_force = 0.0;
};

int run_sweep(const SweepOptions& options);

// Makes the output directory, refusing one that is a file and any of `files` in it that is not a regular file.
void prepare_sweep_dir(const std::string& out_dir, std::initializer_list<const char*> files);
// gnuplot on the script, started without a shell: its path is an argument, never a command line. Its output
// goes to stderr (stdout is the program's report). Returns gnuplot's exit status, or 127 if it cannot start.
int run_gnuplot(const std::filesystem::path& script);
// Plot scripts name no path: these lines set `dir` to the script's own directory (gnuplot's ARG0, set however
// it is started), so a directory's name is data, never gnuplot code, and the script runs from any directory.
inline constexpr const char* kGnuplotScriptDir =
    "dir = ARG0\n"
    "while (strlen(dir) > 0 && dir[strlen(dir):strlen(dir)] ne \"/\") { dir = dir[1:strlen(dir) - 1] }\n";

}  // namespace lever::hil
