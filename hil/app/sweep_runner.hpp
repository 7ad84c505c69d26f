#pragma once
// What every lever-hil sweep does around its runs: the output directory, the runs in parallel with a progress
// line, and the plots.
#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <string>

#include "sweep_table.hpp"

namespace lever::hil {

// Makes the output directory, refusing one that is a file and any of `files` in it that is not a regular file.
void prepare_sweep_dir(const std::string& out_dir, std::initializer_list<const char*> files);
// Plot scripts name no path: these lines set `dir` to the script's own directory (gnuplot's ARG0, set however
// it is started), so a directory's name is data, never gnuplot code, and the script runs from any directory.
inline constexpr const char* kGnuplotScriptDir =
    "dir = ARG0\n"
    "while (strlen(dir) > 0 && dir[strlen(dir):strlen(dir)] ne \"/\") { dir = dir[1:strlen(dir) - 1] }\n";

// Calls run(i) for every i below `count` on `threads` threads, with a progress line on stderr: rewritten in place
// on a terminal, one line every `every` runs otherwise. label(i) names run i in it.
void run_in_parallel(std::size_t count, int threads, std::size_t every, const std::function<void(std::size_t)>& run,
                     const std::function<std::string(std::size_t)>& label);
// Writes the table's sweep.csv and summary.csv and the plot script plots.gp into the directory.
void write_sweep(const std::filesystem::path& dir, const SweepTable& table, const std::string& plot_script);
// Runs the directory's plots.gp; on failure says so and where the CSV files are. Returns the exit code.
int plot_sweep(const std::filesystem::path& dir);

}  // namespace lever::hil
