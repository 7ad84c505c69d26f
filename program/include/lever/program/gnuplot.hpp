#pragma once
// gnuplot started on a script the program wrote, for lever-hil's sweeps and lever-plot's sessions.
#include <filesystem>

namespace lever::program {

// gnuplot on the script, started without a shell: its path is an argument, never a command line. Its output goes
// to stderr (stdout is the program's report). Returns gnuplot's exit status, or 127 if it cannot start.
int run_gnuplot(const std::filesystem::path& script);

}  // namespace lever::program
