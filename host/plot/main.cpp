// lever-plot: a recorded session of a lever pair drawn as the HIL draws its runs. Reads a candump -L recording
// (lever-bridge --record, candump -L) with the levers' status lines if given, or lever-hil run's --trace, and
// writes the decoded CSV files and PNGs (positions and tracking error, force, packet rates, states and faults).
#include <fmt/format.h>
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>

#include "candump_log.hpp"
#include "lever/program/config_file.hpp"
#include "lever/program/exit_codes.hpp"
#include "lever/program/gnuplot.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"
#include "plot_script.hpp"
#include "session.hpp"

namespace {

namespace program = lever::program;
namespace plot = lever::plot;

// A regular file or a FIFO (a recording being written); a directory or a device is refused, never read.
std::ifstream open_input(const std::string& path, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw program::BadInput(fmt::format("{}: cannot read: {}", program::printable(path), std::strerror(errno)));
  if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode))
    throw program::BadInput(
        fmt::format("{}: {}, not {}", program::printable(path), program::file_kind(st.st_mode), what));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw program::BadInput(fmt::format("{}: cannot read: {}", program::printable(path), std::strerror(errno)));
  return in;
}

std::vector<plot::StatusLine> read_status(const std::vector<std::string>& files) {
  std::vector<plot::StatusLine> lines;
  for (const auto& file : files) {
    auto in = open_input(file, "a file of lever-fw --stats-json lines");
    std::string line;
    for (std::size_t number = 1; std::getline(in, line); ++number)
      if (line.find_first_not_of(" \t\r") != std::string::npos)
        lines.push_back(plot::parse_status_line(line, fmt::format("{}:{}", program::printable(file), number)));
  }
  return lines;
}

void print_log_summary(const plot::Session& s, const plot::CandumpLog& log, const std::string& name, int pair) {
  std::size_t frames = 0;
  for (const auto& [message, n] : s.counts) frames += n;
  fmt::print("{}: {} frames of pair {} over {:.2f} s", name, frames, pair, s.duration);
  if (s.other_frames) fmt::print(", {} of other pairs or ids", s.other_frames);
  if (s.decode_errors) fmt::print(", {} that did not decode", s.decode_errors);
  fmt::print("\n  {:<20} {:>8} {:>9}\n", "message", "frames", "per s");
  for (const auto& [message, n] : s.counts) {
    fmt::print("  {:<20} {:>8} {:>9.1f}", message, n, s.duration > 0 ? static_cast<double>(n) / s.duration : 0.0);
    if (message == "LeverMotion") fmt::print("  refresh {}, deadband {}", s.motion_refresh, n - s.motion_refresh);
    if (message == "LeverForce") fmt::print("  refresh {}, deadband {}", s.force_refresh, n - s.force_refresh);
    fmt::print("\n");
  }
  fmt::print("  sent by the HSI {}, by the TOP {} (heartbeats, data, energy and settings frames)\n", s.sent_by[0],
             s.sent_by[1]);
  for (const bool top : {false, true}) {
    const plot::StatusLine* last = nullptr;
    std::size_t count = 0, placed = 0;
    for (const auto& l : s.status)
      if (l.top == top) {
        ++count;
        if (std::isnan(l.t)) continue;
        ++placed;
        last = &l;
      }
    if (count == 0) continue;
    const char* role = top ? "TOP" : "HSI";
    fmt::print("  {} status lines: {}, {} placed in the log by their tx_frames\n", role, count, placed);
    if (last)
      fmt::print(
          "  {} at its last placed status line ({:.3f} s, {}): data_sent {}, refresh_sent {}; in the log by "
          "then: data {}, refresh {}\n",
          role, last->t, last->state, last->data_sent, last->refresh_sent, last->data_in_log, last->refresh_in_log);
  }
  for (const auto& f : s.faults_seen) fmt::print("  faults: {}\n", f);
  for (const auto& f : s.settings_seen) fmt::print("  settings: {}\n", f);
  if (log.bad_lines)
    fmt::print(stderr, "lever-plot: {}: {} of {} lines skipped, not candump -L frames (the first: {})\n", name,
               log.bad_lines, log.lines, log.first_bad.front());
}

int run(const std::string& input, const std::string& out_dir, const std::vector<std::string>& status_files, int pair,
        std::string title, bool draw) {
  namespace fs = std::filesystem;
  const std::string name = program::printable(input);
  if (title.empty()) title = fs::path(input).filename().string();
  auto in = open_input(input, "a candump -L log or a lever-hil trace");
  const auto status = read_status(status_files);

  plot::Session s;
  plot::CandumpLog log;
  if (in.peek() == 't') {  // "t,hsi_angle,...": lever-hil run --trace
    if (!status.empty()) throw program::BadInput("--status goes with a candump -L log, not a lever-hil trace");
    s = plot::session_from_hil_trace(in, name);
  } else {
    log = plot::read_candump(in);
    if (log.frames.empty() && log.bad_lines == 0) throw program::BadInput(fmt::format("{}: empty: no frames", name));
    if (log.frames.empty())
      throw program::BadInput(
          fmt::format("{}: not a candump -L log: none of its {} lines is a frame like "
                      "'(1700000000.000000) can0 101#0011223344556677'",
                      name, log.lines));
    s = plot::session_from_log(log, static_cast<std::uint8_t>(pair), status);
  }

  std::error_code ec;
  if (fs::exists(out_dir, ec) && !fs::is_directory(out_dir, ec))
    throw program::BadInput(fmt::format("--out {} exists and is not a directory", program::printable(out_dir)));
  fs::create_directories(out_dir, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", program::printable(out_dir), ec.message()));
  const fs::path dir(out_dir);
  if (s.source == "candump") program::OutputFile::write_all((dir / "frames.csv").string(), s.frames_csv, "--out");
  program::OutputFile::write_all((dir / "timeline.csv").string(), plot::timeline_csv(s), "--out");
  program::OutputFile::write_all((dir / "rates.csv").string(), plot::rates_csv(s), "--out");
  const plot::PlotScript script = plot::gnuplot_script(s, title);
  program::OutputFile::write_all((dir / "plots.gp").string(), script.text, "--out");

  if (s.source == "candump") {
    print_log_summary(s, log, name, pair);
  } else {
    std::size_t motion = 0, force = 0;
    for (const auto& b : s.rates)
      motion += static_cast<std::size_t>(b.motion), force += static_cast<std::size_t>(b.force);
    fmt::print("{}: lever-hil trace over {:.2f} s: motion frames {} ({:.1f} /s), force frames {} ({:.1f} /s)\n", name,
               s.duration, motion, s.duration > 0 ? static_cast<double>(motion) / s.duration : 0.0, force,
               s.duration > 0 ? static_cast<double>(force) / s.duration : 0.0);
  }
  for (const auto& what : script.left_out) fmt::print("not drawn: {}\n", what);
  if (!draw) return program::kSuccess;
  const int status_code = program::run_gnuplot(dir / "plots.gp");
  if (status_code != 0) {
    fmt::print(stderr, "lever-plot: {}; the CSV files and plots.gp are in {}\n",
               status_code == 127 ? "gnuplot could not be started (install gnuplot-nox for plots)"
                                  : fmt::format("gnuplot failed (exit status {})", status_code),
               program::printable(out_dir));
    return program::kRuntimeFailure;
  }
  std::string pngs;
  for (const auto& png : script.pngs) pngs += (pngs.empty() ? "" : ", ") + program::printable((dir / png).string());
  fmt::print("plots: {}\n", pngs);
  return program::kSuccess;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Draws a recorded session of a lever pair as the HIL draws its runs: from a candump -L recording "
      "(lever-bridge --record, candump -L) and, if given, the levers' status lines (lever-fw --stats-json), or "
      "from lever-hil run --trace. Writes into --out: frames.csv (a log's frames of the pair, decoded by the "
      "lever protocol, by named columns), timeline.csv (every 10 ms: positions, tracking error, force measured "
      "at the TOP and displayed at the HSI, states, faults), rates.csv (data frames per second per direction, "
      "and those the deadband sent), plots.gp and its PNGs. Prints frames per message and their rates."};
  std::string input, out_dir, title;
  std::vector<std::string> status_files;
  int pair = 0;
  bool no_plots = false;
  app.add_option("INPUT", input, "a candump -L log, or a lever-hil run --trace CSV")
      ->required()
      ->check(program::path());
  app.add_option("--out", out_dir, "the directory to write into (made if missing)")->required()->check(program::path());
  app.add_option("--status", status_files, "a file of one lever's lever-fw --stats-json lines (repeat for both)")
      ->check(program::path());
  app.add_option("--pair", pair, "the lever pair to draw")->check(CLI::Range(0, 15))->default_val(0);
  app.add_option("--title", title, "the plots' title (default: the input's file name)");
  app.add_flag("--no-plots", no_plots, "write the CSV files and plots.gp, do not run gnuplot");
  program::describe(app, "lever-plot");
  if (const auto code = program::parse(app, argc, argv)) return *code;
  try {
    return run(input, out_dir, status_files, pair, title, !no_plots);
  } catch (const program::BadInput& e) {
    fmt::print(stderr, "lever-plot: {}\n", e.what());
    return program::kBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "lever-plot: {}\n", e.what());
    return program::kRuntimeFailure;
  }
}
