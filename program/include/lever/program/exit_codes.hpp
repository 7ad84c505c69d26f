#pragma once
// The exit codes every program of the testbed keeps, and the line each one's --help ends with.
#include <stdexcept>
#include <string>

namespace lever::program {

inline constexpr int kSuccess = 0;
inline constexpr int kRuntimeFailure = 1;  // the input was fine; the world was not (a device, a disk, a peer)
inline constexpr int kBadInput = 2;        // arguments, a configuration or an input file the program refuses

inline constexpr const char* kExitCodesHelp =
    "Exit codes: 0 success, 1 runtime failure, 2 bad input (arguments, configuration or input files).";

// Bad input found after parsing (an input file, an output path, values that disagree): exit 2. Derives from
// std::invalid_argument so that the programs' existing handlers for it keep mapping it to exit 2.
class BadInput : public std::invalid_argument {
 public:
  explicit BadInput(const std::string& message) : std::invalid_argument(message) {}
};

}  // namespace lever::program
