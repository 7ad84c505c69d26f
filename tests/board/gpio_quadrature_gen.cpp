// lever-gpio-quadrature-gen: plays an incremental encoder on a gpio-sim chip by writing pull-up/pull-down to
// its lines' sysfs `pull` files, so that a real libgpiod consumer sees real kernel edge events. Runs the steps
// given, in order, then writes a JSON summary (what was generated, where the lines ended).
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "lever/program/parse.hpp"

namespace {

struct GenError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::uint64_t now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000u + static_cast<std::uint64_t>(ts.tv_nsec);
}

// One simulated line: its pull file kept open, its level as we last drove it.
class SimLine {
 public:
  SimLine(const std::string& dir, unsigned offset) : path_(dir + "/sim_gpio" + std::to_string(offset)) {
    std::ifstream value(path_ + "/value");
    int v = -1;
    if (!(value >> v) || (v != 0 && v != 1)) throw GenError(path_ + "/value: cannot read the line's level");
    level_ = v == 1;
    fd_ = ::open((path_ + "/pull").c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) throw GenError(path_ + "/pull: " + std::strerror(errno));
  }
  SimLine(const SimLine&) = delete;
  SimLine& operator=(const SimLine&) = delete;
  ~SimLine() { ::close(fd_); }

  bool level() const { return level_; }
  void set(bool level) {
    const char* text = level ? "pull-up" : "pull-down";
    // Each write is one store into the attribute; from offset 0, as sysfs expects.
    if (::pwrite(fd_, text, std::strlen(text), 0) < 0) throw GenError(path_ + "/pull: " + std::strerror(errno));
    level_ = level;
  }
  void toggle() { set(!level_); }

 private:
  std::string path_;
  int fd_ = -1;
  bool level_ = false;
};

struct Summary {
  std::uint64_t edges = 0;     // A/B level changes written
  std::int64_t position = 0;   // quadrature steps, forward positive (glitches and bounces not counted)
  std::uint64_t glitches = 0;  // two-state jumps
  std::vector<std::int64_t> index_at;
};

class Generator {
 public:
  Generator(const std::string& dir, unsigned a, unsigned b, std::optional<unsigned> z, double rate)
      : a_(dir, a), b_(dir, b) {
    if (z) {
      z_.emplace(dir, *z);
      z_->set(false);  // an index pulse is a rise from low
    }
    set_rate(rate);
    next_ = now_ns();
  }

  void set_rate(double rate) { period_ns_ = rate > 0 ? static_cast<std::uint64_t>(1e9 / rate) : 0; }
  // Pace groups of `edges` back to back, one sleep per group: a sleep per edge costs more than the edge in an
  // emulated guest, which caps the rate it can generate.
  void set_batch(unsigned edges) { batch_ = edges > 0 ? edges : 1; }

  // Gray order 00 -> 01 -> 11 -> 10 -> 00 is forward: from equal levels B moves, from unequal A moves.
  void step(bool forward) {
    const bool equal = a_.level() == b_.level();
    SimLine& line = (equal == forward) ? b_ : a_;
    pace();
    line.toggle();
    ++s_.edges;
    s_.position += forward ? 1 : -1;
  }

  void index() {
    if (!z_) throw GenError("index: no index line given (--z)");
    pace();
    z_->set(true);
    z_->set(false);
    s_.index_at.push_back(s_.position);
  }

  // Both lines at once: a jump no quadrature signal makes; the decoded direction is undefined.
  void glitch() {
    pace();
    a_.toggle();
    b_.toggle();
    s_.edges += 2;
    ++s_.glitches;
  }

  void bounce(char which, unsigned times) {
    SimLine& line = which == 'a' ? a_ : b_;
    for (unsigned i = 0; i < times; ++i) {
      pace();
      line.toggle();
      ++s_.edges;
    }
  }

  void pause(unsigned ms) {
    timespec ts{static_cast<time_t>(ms / 1000), static_cast<long>(ms % 1000) * 1'000'000L};
    ::nanosleep(&ts, nullptr);
    next_ = now_ns();
  }

  std::string levels() const { return std::string{a_.level() ? '1' : '0', b_.level() ? '1' : '0'}; }
  const Summary& summary() const { return s_; }

 private:
  // At most the rate, from deadlines on a fixed grid; but a late generator (the guest's vCPU stalled on a busy
  // host) starts a new grid from now rather than catching up in a burst the test did not ask for.
  void pace() {
    if (period_ns_ == 0) return;
    if (++in_batch_ < batch_) return;
    in_batch_ = 0;
    next_ += period_ns_ * batch_;
    if (const std::uint64_t now = now_ns(); next_ < now) next_ = now;
    timespec ts{static_cast<time_t>(next_ / 1'000'000'000u), static_cast<long>(next_ % 1'000'000'000u)};
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }

  SimLine a_, b_;
  std::optional<SimLine> z_;
  std::uint64_t period_ns_ = 0;
  std::uint64_t next_ = 0;
  unsigned batch_ = 1, in_batch_ = 0;
  Summary s_;
};

unsigned parse_count(const std::string& step, std::string_view digits) {
  unsigned n = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), n);
  if (ec != std::errc{} || end != digits.data() + digits.size()) throw GenError("step '" + step + "': bad number");
  return n;
}

void run_step(Generator& g, const std::string& step) {
  const std::string_view s(step);
  if (s.size() > 1 && (s[0] == '+' || s[0] == '-')) {
    const unsigned n = parse_count(step, s.substr(1));
    for (unsigned i = 0; i < n; ++i) g.step(s[0] == '+');
  } else if (s == "index") {
    g.index();
  } else if (s == "glitch") {
    g.glitch();
  } else if (s.rfind("rate=", 0) == 0) {
    g.set_rate(parse_count(step, s.substr(5)));
  } else if (s.rfind("batch=", 0) == 0) {
    g.set_batch(parse_count(step, s.substr(6)));
  } else if (s.rfind("pause=", 0) == 0) {
    g.pause(parse_count(step, s.substr(6)));
  } else if (s.rfind("bounce:a=", 0) == 0 || s.rfind("bounce:b=", 0) == 0) {
    g.bounce(s[7], parse_count(step, s.substr(9)));
  } else {
    throw GenError("unknown step '" + step + "'");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Drive a gpio-sim chip's lines as a quadrature encoder. Steps, in order:\n"
      "  +N / -N        N edges forward / back (Gray order 00 01 11 10 is forward)\n"
      "  index          one pulse on the index line at the current position\n"
      "  glitch         A and B flip back to back (a jump of two states)\n"
      "  bounce:a=N     line A (or b) toggles N times, paced\n"
      "  rate=R         R edges/s from here on (0: as fast as the writes go)\n"
      "  batch=N        pace N edges at a time, back to back (default 1)\n"
      "  pause=MS       wait MS milliseconds",
      "lever-gpio-quadrature-gen"};
  std::string dir;
  unsigned a = 0, b = 1;
  std::optional<unsigned> z;
  double rate = 2000;
  std::string summary_path;
  std::vector<std::string> steps;
  app.add_option("--dir", dir, "the chip's sysfs directory, /sys/devices/platform/<device>/<chip>")->required();
  app.add_option("--a", a, "offset of line A")->capture_default_str();
  app.add_option("--b", b, "offset of line B")->capture_default_str();
  app.add_option("--z", z, "offset of the index line");
  app.add_option("--rate", rate, "edges per second at the start (0: unpaced)")->capture_default_str();
  app.add_option("--summary", summary_path, "write the JSON summary here instead of stdout");
  app.add_option("steps", steps, "the steps")->required();
  if (const auto code = lever::program::parse(app, argc, argv)) return *code;

  try {
    Generator g(dir, a, b, z, rate);
    const std::uint64_t start = now_ns();
    for (const auto& step : steps) run_step(g, step);
    const double elapsed = static_cast<double>(now_ns() - start) * 1e-9;
    const Summary& s = g.summary();
    std::string index_at;
    for (const auto p : s.index_at) index_at += (index_at.empty() ? "" : ",") + std::to_string(p);
    const std::string json =
        fmt::format(R"({{"edges":{},"position":{},"glitches":{},"levels":"{}","index_at":[{}],"elapsed_s":{:.3f}}})",
                    s.edges, s.position, s.glitches, g.levels(), index_at, elapsed) +
        "\n";
    if (summary_path.empty()) {
      fmt::print("{}", json);
    } else {
      std::ofstream out(summary_path);
      out << json;
      if (!out) throw GenError(summary_path + ": cannot write the summary");
    }
  } catch (const GenError& e) {
    fmt::print(stderr, "lever-gpio-quadrature-gen: {}\n", e.what());
    return 1;
  }
  return 0;
}
