#pragma once
// Command-line parsing shared by lever-codec, lever-hil and lever-bridge: help on stdout with exit 0, any other
// problem as one line on stderr with exit 2, the same for every program.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <optional>

namespace lever::program {

inline constexpr int kBadInput = 2;

// Returns the exit code when the program should stop now (0 after help, kBadInput after an error); nullopt when
// it should go on.
inline std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::CallForAllHelp&) {
    fmt::print("{}", app.help("", CLI::AppFormatMode::All));
    return 0;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, of the program or of a subcommand (help() picks the selected one)
      fmt::print("{}", app.help());
      return 0;
    }
    fmt::print(stderr, "{}: {}\n", app.get_name(), e.what());
    return kBadInput;
  }
}

}  // namespace lever::program
