// lever-view: a live view of the lever pairs on a CAN bus, for a terminal (over ssh on a board or the host).
#include <fcntl.h>
#include <fmt/format.h>
#include <langinfo.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <clocale>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "can_reader.hpp"
#include "curses_screen.hpp"
#include "lever/board/interface_name.hpp"
#include "lever/board/socketcan.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"
#include "live_monitor.hpp"
#include "refresh_meter.hpp"
#include "snapshot_json.hpp"
#include "status_reader.hpp"

namespace {

namespace program = lever::program;
namespace board = lever::board;
namespace view = lever::view;

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "lever-view: %s\n", message.c_str());
  return code;
}

// What to do when the CAN socket cannot be opened, as lever-bridge says it.
std::string can_hint(int error, const std::string& interface) {
  if (error == EAFNOSUPPORT)
    return "; this kernel has no CAN protocol family loaded: `modprobe can-raw` (a virtual bus also needs "
           "`modprobe vcan`)";
  if (error == ENODEV)
    return fmt::format(
        "; see `ip link show`; a virtual bus: `modprobe vcan && ip link add dev {0} type vcan && ip "
        "link set {0} up`",
        interface);
  return "";
}

struct Options {
  std::string can;
  std::vector<std::string> status;
  std::optional<unsigned> pair;
  unsigned bitrate = 1'000'000;
  double refresh_hz = 10.0;
  std::optional<double> duration_s;
  bool json = false;
  bool ascii = false;
};

// Opens a status input: "-" is stdin, anything else a file or FIFO that must exist (a FIFO opened without
// waiting for its writer).
std::optional<std::string> open_status(const std::string& path, board::UniqueFd& fd) {
  if (path == "-") {
    fd.reset(::dup(STDIN_FILENO));
    if (!fd) return fmt::format("--status -: {}", std::strerror(errno));
    return std::nullopt;
  }
  fd.reset(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (!fd) return fmt::format("--status {}: {}", program::printable(path, 200), std::strerror(errno));
  struct stat st {};
  if (::fstat(fd.get(), &st) == 0 && S_ISDIR(st.st_mode))
    return fmt::format("--status {}: is a directory", program::printable(path, 200));
  return std::nullopt;
}

int run_json(view::LiveMonitor& live, const Options& options) {
  const auto period = std::chrono::duration<double>(1.0 / options.refresh_hz);
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  while (!g_stop.load()) {
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
    const bool last = options.duration_s &&
                      std::chrono::steady_clock::now() - start >= std::chrono::duration<double>(*options.duration_s);
    std::string text;
    {
      const std::lock_guard lock(live.mutex);
      text = view::to_json(live.monitor.snapshot(view::realtime_us()), live.reader).dump();
    }
    std::fprintf(stdout, "%s\n", text.c_str());
    std::fflush(stdout);
    if (last) break;
  }
  return 0;
}

int run_screen(view::LiveMonitor& live, const Options& options, bool utf8) {
  using Clock = std::chrono::steady_clock;
  view::CursesScreen screen;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / options.refresh_hz));
  const auto start = Clock::now();
  view::Snapshot snapshot;
  view::ReaderState reader;
  view::RefreshMeter meter;
  bool frozen = false;
  bool take = true;
  bool early = false;  // drawn at once for a key, between two scheduled pictures
  auto next = start;
  while (!g_stop.load()) {
    if (take) {
      const std::lock_guard lock(live.mutex);
      snapshot = live.monitor.snapshot(view::realtime_us());
      reader = live.reader;
    }
    view::ScreenOptions screen_options{screen.columns(), utf8, frozen, static_cast<double>(options.bitrate),
                                       std::nullopt};
    screen_options.pictures_per_s = meter.per_second();
    screen.draw(view::render(snapshot, reader, screen_options));
    const auto drawn = Clock::now();
    meter.on_draw(std::chrono::duration_cast<std::chrono::microseconds>(drawn - start).count());
    // Pictures on a fixed schedule, so drawing time does not slow the rate; after a stall (a suspended
    // terminal), the schedule starts again from now rather than catching up.
    if (!early) next = next + period < drawn ? drawn + period : next + period;
    early = false;
    take = !frozen;
    // Keys until the next picture is due.
    for (auto now = Clock::now(); now < next && !g_stop.load(); now = Clock::now()) {
      const int key =
          screen.key(static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(next - now).count() + 1));
      if (key == 'q' || key == 'Q') return 0;
      if (key == 'f' || key == 'F' || key == ' ') {
        frozen = !frozen;
        take = !frozen;
        early = true;
        break;
      }
      if (key == 'r' || key == 'R') {
        const std::lock_guard lock(live.mutex);
        live.monitor.reset();
        take = true;
        early = true;
        break;
      }
      if (key == view::CursesScreen::kResize) {
        early = true;
        break;
      }
    }
    if (options.duration_s && Clock::now() - start >= std::chrono::duration<double>(*options.duration_s)) break;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "A live view of the lever pairs on a CAN interface, decoded by the lever protocol (common/protocol/lever.dbc):\n"
      "per lever its role, state, homing, latched faults and newest data; per direction the data frames a second\n"
      "as a share of the 1 kHz sample rate and what the deadband saves; frames lost or out of order; the bus load;\n"
      "the last 20 s of the HSI's position and the TOP's force. --status adds what only the levers' status lines\n"
      "say (the TOP's position, the motor torques) and the bridges'. Keys: f or space freeze, r reset counters,\n"
      "q quit."};
  program::describe(app, "lever-view");
  Options options;
  app.add_option("--can", options.can, "SocketCAN interface to listen on, e.g. can0 or vcan0")->required();
  app.add_option("--status", options.status,
                 "status lines to show beside the bus (repeatable): lever-fw's or lever-bridge's --stats-json, from a "
                 "file (followed as it grows), a FIFO, or '-' (stdin)")
      ->check(program::path());
  app.add_option("--pair", options.pair, "show only this pair (0-15); default: every pair seen")
      ->check(program::whole(0, lever::protocol::kPairCount - 1, "a pair number"));
  app.add_option("--bitrate", options.bitrate, "the bus's bit rate in bits/s, for the bus load")
      ->check(program::whole(10'000, 1'000'000, "a bit rate in bits/s"))
      ->default_str("1000000");
  app.add_option("--refresh-hz", options.refresh_hz, "pictures (or JSON lines) a second")
      ->check(program::number({1.0, 50.0, false, false, "a rate in Hz"}))
      ->default_str("10");
  app.add_option("--duration", options.duration_s, "stop after this many seconds (default: until q or a signal)")
      ->check(program::number({0.0, 1e6, true, false, "a duration in seconds"}));
  app.add_flag("--json", options.json,
               "no screen: one JSON object a refresh on stdout, the same figures (docs/lever-view.md)");
  app.add_flag("--ascii", options.ascii, "sparklines in ASCII, not in Unicode block elements");
  if (const auto stop = program::parse(app, argc, argv)) return *stop;

  if (const auto problem = board::interface_name_problem(options.can))
    return fail(program::kBadInput, fmt::format("--can: {}", *problem));
  if (std::count(options.status.begin(), options.status.end(), std::string("-")) > 1)
    return fail(program::kBadInput, "--status -: stdin can be given once");
  std::setlocale(LC_ALL, "");
  const bool utf8 = !options.ascii && std::strcmp(nl_langinfo(CODESET), "UTF-8") == 0;
  if (!options.json && !isatty(STDOUT_FILENO))
    return fail(program::kBadInput, "stdout is not a terminal: the screen needs one (--json prints lines instead)");

  std::vector<board::UniqueFd> status_fds(options.status.size());
  for (std::size_t i = 0; i < options.status.size(); ++i)
    if (const auto problem = open_status(options.status[i], status_fds[i])) return fail(program::kBadInput, *problem);

  board::SocketCanConfig can_config;
  can_config.interface = options.can;
  auto can = board::SocketCan::open(can_config);
  if (!can) {
    const int error = can.error().errno_value;
    const std::string message = can.error().message + can_hint(error, options.can);
    // A missing interface is the user's to fix, as a bad option is.
    return fail(error == ENODEV ? program::kBadInput : program::kRuntimeFailure, message);
  }

  for (const int s : {SIGINT, SIGTERM, SIGHUP}) std::signal(s, on_signal);
  view::MonitorConfig config;
  config.bitrate = options.bitrate;
  if (options.pair) config.pair = static_cast<std::uint8_t>(*options.pair);
  view::LiveMonitor live(config);
  live.reader.interface = options.can;
  try {
    view::CanReader reader(std::move(can).value(), live);
    std::vector<std::unique_ptr<view::StatusReader>> status_readers;
    for (std::size_t i = 0; i < status_fds.size(); ++i)
      status_readers.push_back(std::make_unique<view::StatusReader>(std::move(status_fds[i]), i, live));
    return options.json ? run_json(live, options) : run_screen(live, options, utf8);
  } catch (const std::exception& e) {
    return fail(program::kRuntimeFailure, e.what());
  }
}
