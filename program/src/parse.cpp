#include "lever/program/parse.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <string_view>

#include "lever/program/text.hpp"

namespace lever::program {
namespace {

std::string subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const auto* sub : app.get_subcommands({})) names.push_back(sub->get_name());
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return out;
}

bool names_subcommand(const CLI::App& app, const std::string& word) {
  for (const auto* sub : app.get_subcommands({}))
    if (sub->check_name(word)) return true;
  return false;
}

// CLI11 says "--p: must be ..."; the option's own terms read "--p must be ...".
std::string tidy(std::string message) {
  if (const auto at = message.find(": must be "); at != std::string::npos && message.find(' ') > at)
    message.erase(at, 1);
  return message;
}

}  // namespace

std::string version() { return LEVER_PROGRAM_VERSION; }

CLI::Validator path() {
  return CLI::Validator([](std::string& text) { return text.empty() ? std::string("must be a path, got ''") : ""; },
                        "");
}

void describe(CLI::App& app, const std::string& name) {
  app.name(name);
  app.footer(kExitCodesHelp);
  app.set_version_flag("--version", name + " " + version());
}

std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  // A word where a subcommand goes that names none: CLI11 would say "A subcommand is required" or "The
  // following arguments were not expected".
  if (argc > 1 && !app.get_subcommands({}).empty() && argv[1][0] != '-' && !names_subcommand(app, argv[1])) {
    fmt::print(stderr, "{}: unknown subcommand '{}'; expected {} (see --help)\n", app.get_name(), printable(argv[1]),
               subcommand_names(app));
    return kBadInput;
  }
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::CallForAllHelp&) {
    fmt::print("{}", app.help("", CLI::AppFormatMode::All));
    return 0;
  } catch (const CLI::CallForVersion& e) {  // its message is the version string
    fmt::print("{}\n", e.what());
    return 0;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, of the program or of a subcommand (help() picks the selected one)
      fmt::print("{}", app.help());
      return 0;
    }
    fmt::print(stderr, "{}: {}\n", app.get_name(), printable(tidy(e.what()), 400));
    return kBadInput;
  }
}

}  // namespace lever::program
