#pragma once
// Command-line parsing shared by every program: help on stdout with exit 0, any other problem as one line on
// stderr with exit 2, the exit codes in every --help and --version everywhere.
#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "lever/program/exit_codes.hpp"

namespace lever::program {

// The testbed's version, from CMake's project().
std::string version();

// Names the program, adds --version and puts the exit codes at the foot of its --help (and its subcommands').
void describe(CLI::App& app, const std::string& name);

// A file or directory name: refuses the empty string, which would otherwise mean "no file" in silence.
CLI::Validator path();

// Returns the exit code when the program should stop now (0 after help or --version, kBadInput after an
// error); nullopt when it should go on. A first argument that is no option and no subcommand is reported as
// a misspelt subcommand, naming the ones there are.
std::optional<int> parse(CLI::App& app, int argc, char** argv);

}  // namespace lever::program
