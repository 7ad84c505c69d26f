// GpioEncoder against the real kernel GPIO stack: a gpio-sim chip in the kernel rig's guest, its lines driven by
// lever-gpio-quadrature-gen. Run by tests/kernel/gpio_encoder.sh, which makes the chip and sets:
//   LEVER_GPIO_CHIP   the chip's name (gpiochipN)      LEVER_GPIO_LABEL  its label
//   LEVER_GPIO_SYSFS  its sysfs directory (pull files) LEVER_GPIO_GEN    the generator
// The chip's lines: 0 "enc-a", 1 "enc-b", 2 "enc-z". The guest's clock is emulated and slow: the tests assert
// what was delivered, never how fast.
#include <dlfcn.h>
#include <linux/gpio.h>
#include <pthread.h>
#include <sched.h>
#include <spawn.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "lever/board/gpio_encoder.hpp"
#include "lever/fw/lever.hpp"

extern char** environ;

// Every value read of a GPIO line, whatever libgpiod call made it, ends in this ioctl: counted here by the thread
// that made it (this executable's ioctl stands in for libc's in libgpiod too), so a test can tell whether the
// thread that drains, the loop's, ever reads a value.
namespace {
std::atomic<std::uint64_t> value_reads_on_main{0};
std::atomic<std::uint64_t> value_reads_elsewhere{0};
}  // namespace

extern "C" int ioctl(int fd, unsigned long request, ...) noexcept {
  using Real = int (*)(int, unsigned long, ...);
  static const Real real = reinterpret_cast<Real>(::dlsym(RTLD_NEXT, "ioctl"));
  std::va_list args;
  va_start(args, request);
  void* arg = va_arg(args, void*);
  va_end(args);
  if (request == GPIOHANDLE_GET_LINE_VALUES_IOCTL) {
    (::gettid() == ::getpid() ? value_reads_on_main : value_reads_elsewhere).fetch_add(1, std::memory_order_relaxed);
  }
  return real(fd, request, arg);
}

using lever::board::GpioEncoder;
using lever::board::GpioEncoderConfig;
using lever::board::LineRef;
using lever::fw::AbState;
using lever::fw::EncoderEdge;

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') FAIL(name << " is not set: run this through tests/kernel/gpio_encoder.sh");
  return v;
}

// The test's own decoder, independent of the firmware core's: Gray order 00 -> 01 -> 11 -> 10 -> 00 counts up,
// a jump of two states is illegal and counts nothing.
class Decoder {
 public:
  explicit Decoder(AbState start) : state_(start) {}
  void feed(AbState levels) {
    static constexpr int kIllegal = 9;
    static constexpr int table[4][4] = {
        {0, +1, -1, kIllegal}, {-1, 0, kIllegal, +1}, {+1, kIllegal, 0, -1}, {kIllegal, -1, +1, 0}};
    const int step = table[state_][levels];
    if (step == kIllegal) {
      ++illegal_;
    } else {
      count_ += step;
    }
    state_ = levels;
  }
  std::int64_t count() const { return count_; }
  std::uint64_t illegal() const { return illegal_; }

 private:
  AbState state_;
  std::int64_t count_ = 0;
  std::uint64_t illegal_ = 0;
};

struct GenSummary {
  std::uint64_t edges = 0;
  std::int64_t position = 0;
  AbState levels = 0;
  std::vector<std::int64_t> index_at;
  double elapsed_s = 0;
};

GpioEncoder open_or_fail(const GpioEncoderConfig& config) {
  auto r = GpioEncoder::open(config);
  if (!r.ok()) FAIL("open: " << r.error().message);
  return std::move(r).value();
}

// Runs the generator with `steps` to its end. With `each_tick`, calls it every millisecond while the generator
// runs (the firmware's tick); without, the reader is stalled for the whole run.
GenSummary run_generator(const std::vector<std::string>& steps, const std::function<void()>& each_tick) {
  const std::string summary_path =
      std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + "/gpio-gen-summary.json";
  std::vector<std::string> args{
      env("LEVER_GPIO_GEN"), "--dir",     env("LEVER_GPIO_SYSFS"), "--a", "0", "--b", "1", "--z", "2",
      "--summary",           summary_path};
  args.insert(args.end(), steps.begin(), steps.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  REQUIRE(::posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) == 0);
  int status = 0;
  if (each_tick) {
    timespec next{};
    ::clock_gettime(CLOCK_MONOTONIC, &next);
    for (;;) {
      each_tick();
      const pid_t done = ::waitpid(pid, &status, WNOHANG);
      if (done < 0) FAIL("waitpid on the generator failed");
      if (done == pid) break;
      next.tv_nsec += 1'000'000;
      if (next.tv_nsec >= 1'000'000'000) {
        next.tv_nsec -= 1'000'000'000;
        ++next.tv_sec;
      }
      ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    }
  } else {
    REQUIRE(::waitpid(pid, &status, 0) == pid);
  }
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  std::ifstream in(summary_path);
  const auto j = nlohmann::json::parse(in);
  GenSummary s;
  s.edges = j.at("edges");
  s.position = j.at("position");
  const std::string levels = j.at("levels");
  s.levels = lever::fw::ab(levels[0] == '1', levels[1] == '1');
  s.index_at = j.at("index_at").get<std::vector<std::int64_t>>();
  s.elapsed_s = j.at("elapsed_s");
  return s;
}

class Session {
 public:
  explicit Session(const GpioEncoderConfig& config)
      : encoder_(open_or_fail(config)),
        decoder_(encoder_.levels()),
        main_reads_at_open_(value_reads_on_main.load()),
        other_reads_at_open_(value_reads_elsewhere.load()) {}

  GenSummary generate(const std::vector<std::string>& steps, bool drain_meanwhile) {
    return run_generator(steps, drain_meanwhile ? std::function<void()>([this] { drain(); }) : nullptr);
  }

  void drain() {
    std::array<EncoderEdge, 256> buffer{};
    lever::test::alloc_count_begin();
    const auto d = encoder_.drain_edges(buffer.data(), buffer.size());
    allocations_ += lever::test::alloc_count_end();
    ++drains_;
    lost_ += d.lost;
    for (std::size_t i = 0; i < d.count; ++i) {
      if (buffer[i].index) {
        index_at_.push_back(decoder_.count());
      } else {
        decoder_.feed(buffer[i].levels);
      }
    }
  }

  // Some ticks more, so that straggling events and the last level check are through.
  void settle(int ticks = 50) {
    for (int i = 0; i < ticks; ++i) {
      timespec ms{0, 1'000'000};
      ::nanosleep(&ms, nullptr);
      drain();
    }
  }

  GpioEncoder& encoder() { return encoder_; }
  const Decoder& decoder() const { return decoder_; }
  std::uint64_t lost() const { return lost_; }
  std::uint64_t allocations() const { return allocations_; }
  std::uint64_t drains() const { return drains_; }
  const std::vector<std::int64_t>& index_at() const { return index_at_; }
  // Value reads since open by the thread that drains (the tests' main thread), and by any other.
  std::uint64_t value_reads_on_caller() const { return value_reads_on_main.load() - main_reads_at_open_; }
  std::uint64_t value_reads_elsewhere_since_open() const { return value_reads_elsewhere.load() - other_reads_at_open_; }

  void report(const char* what, const GenSummary& s) const {
    const auto& st = encoder_.stats();
    const std::string allocs = std::to_string(allocations_);
    std::printf(
        "measured: %s: generated %llu edges in %.2f s (%.0f edges/s); delivered %llu edges, %llu index; decoded "
        "%lld; lost %llu (fifo_full %llu, impossible %llu, reordered %llu, resyncs %llu); level checks %llu; "
        "value reads on the draining thread %llu, on others %llu; illegal transitions %llu; drains %llu; "
        "allocations in drains %s\n",
        what, static_cast<unsigned long long>(s.edges), s.elapsed_s,
        s.elapsed_s > 0 ? static_cast<double>(s.edges) / s.elapsed_s : 0.0, static_cast<unsigned long long>(st.edges),
        static_cast<unsigned long long>(st.index_edges), static_cast<long long>(decoder_.count()),
        static_cast<unsigned long long>(lost_), static_cast<unsigned long long>(st.fifo_full),
        static_cast<unsigned long long>(st.impossible), static_cast<unsigned long long>(st.reordered),
        static_cast<unsigned long long>(st.resyncs), static_cast<unsigned long long>(st.level_checks),
        static_cast<unsigned long long>(value_reads_on_caller()),
        static_cast<unsigned long long>(value_reads_elsewhere_since_open()),
        static_cast<unsigned long long>(decoder_.illegal()), static_cast<unsigned long long>(drains_), allocs.c_str());
    std::fflush(stdout);
  }

 private:
  GpioEncoder encoder_;
  Decoder decoder_;
  std::uint64_t lost_ = 0;
  std::uint64_t allocations_ = 0;
  std::uint64_t drains_ = 0;
  std::vector<std::int64_t> index_at_;
  std::uint64_t main_reads_at_open_;
  std::uint64_t other_reads_at_open_;
};

// By label and line names, as a board's config would say it.
GpioEncoderConfig by_label_and_names() {
  GpioEncoderConfig c;
  c.chip = env("LEVER_GPIO_LABEL");
  c.line_a = LineRef::parse("enc-a");
  c.line_b = LineRef::parse("enc-b");
  c.line_z = LineRef::parse("enc-z");
  c.consumer = "lever-gpio-sim-test";
  return c;
}

// By device path and offsets.
GpioEncoderConfig by_path_and_offsets() {
  GpioEncoderConfig c;
  c.chip = "/dev/" + env("LEVER_GPIO_CHIP");
  c.line_a = LineRef::offset(0);
  c.line_b = LineRef::offset(1);
  c.line_z = LineRef::offset(2);
  return c;
}

}  // namespace

TEST_CASE("paced quadrature is counted exactly: 4000 edges forward, then 1500 back, at 2000 edges/s") {
  Session s(by_label_and_names());
  const auto gen = s.generate({"rate=2000", "+4000", "-1500"}, true);
  s.settle();
  s.report("paced 4000 forward, 1500 back", gen);
  REQUIRE(gen.edges == 5500);
  REQUIRE(gen.position == 2500);
  CHECK(s.lost() == 0);
  CHECK(s.decoder().illegal() == 0);
  CHECK(s.encoder().stats().edges == 5500);
  CHECK(s.decoder().count() == 2500);
  CHECK(s.encoder().levels() == gen.levels);
  // The level check ran all along and never found the lines elsewhere.
  CHECK(s.encoder().stats().level_checks > 100);
  CHECK(s.encoder().stats().resyncs == 0);
  CHECK(s.allocations() == 0);
  // ... with every value read on the encoder's own thread.
  CHECK(s.value_reads_on_caller() == 0);
  CHECK(s.value_reads_elsewhere_since_open() >= 2 * s.encoder().stats().level_checks);
}

namespace {

// The calling thread as lever-fw's service starts it (SCHED_FIFO 50), and nice -5, which a SCHED_OTHER thread
// created from it would keep; as it was again at the end of the scope. Only root may.
class RealtimeCaller {
 public:
  RealtimeCaller() {
    ::pthread_getschedparam(::pthread_self(), &policy_, &param_);
    nice_ = ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()));
    sched_param fifo{};
    fifo.sched_priority = 50;
    applied_ = ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), -5) == 0 &&
               ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &fifo) == 0;
  }
  ~RealtimeCaller() {
    ::pthread_setschedparam(::pthread_self(), policy_, &param_);
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), nice_);
  }
  RealtimeCaller(const RealtimeCaller&) = delete;
  RealtimeCaller& operator=(const RealtimeCaller&) = delete;
  bool applied() const { return applied_; }

 private:
  int policy_ = SCHED_OTHER;
  sched_param param_{};
  int nice_ = 0;
  bool applied_ = false;
};

// The id of this process's thread called `name`, 0 if none.
pid_t thread_named(const std::string& name) {
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string line;
    std::getline(comm, line);
    if (line == name) return static_cast<pid_t>(std::stol(task.path().filename().string()));
  }
  return 0;
}

}  // namespace

TEST_CASE("level checks read the values on the encoder's own ordinary thread, never on the thread that drains") {
  // On a real-time caller, as lever-fw's loop is: the reader must drop the priority it would inherit.
  const RealtimeCaller caller;
  Session s(by_label_and_names());
  s.settle(300);  // the lines stand still: a level check is asked for whenever none is pending
  s.report("300 drains, lines idle, the caller at SCHED_FIFO 50", GenSummary{});
  const auto& st = s.encoder().stats();
  CHECK(st.level_checks > 100);
  CHECK(s.lost() == 0);
  CHECK(s.allocations() == 0);
  CHECK(s.value_reads_on_caller() == 0);
  // Two reads per check: the counting sees the reads, so the 0 above is no blind spot.
  CHECK(s.value_reads_elsewhere_since_open() >= 2 * st.level_checks);
  const pid_t reader = thread_named("lever-enc-lvl");
  REQUIRE(reader != 0);
  if (caller.applied()) {
    CHECK(::sched_getscheduler(reader) == SCHED_OTHER);
    CHECK(::getpriority(PRIO_PROCESS, static_cast<id_t>(reader)) == 0);
  } else {
    WARN("not root: the reader's scheduling is not checked");
  }
}

TEST_CASE("index rises are delivered where the index line rose") {
  Session s(by_path_and_offsets());
  const auto gen = s.generate({"rate=2000", "+100", "index", "+300", "index", "-150", "index", "-250", "index"}, true);
  s.settle();
  s.report("index pulses", gen);
  REQUIRE(gen.index_at == std::vector<std::int64_t>{100, 400, 250, 0});
  CHECK(s.lost() == 0);
  CHECK(s.encoder().stats().index_edges == 4);
  CHECK(s.index_at() == gen.index_at);
  CHECK(s.decoder().count() == gen.position);
}

TEST_CASE("a burst the reader cannot keep up with is reported as loss, never as a silently wrong count") {
  SECTION("reader stalled through the whole burst: both FIFOs overflow") {
    Session s(by_label_and_names());
    // 400 edges bring the lines back to where they started: only the full FIFOs can tell that 368 are missing.
    const auto gen = s.generate({"rate=0", "+400"}, false);
    s.settle();
    s.report("burst of 400, reader stalled", gen);
    CHECK(s.lost() > 0);
    CHECK(s.encoder().stats().fifo_full >= 2);
    CHECK(s.decoder().count() != gen.position);  // what the loss report is for
    CHECK(s.encoder().levels() == gen.levels);

    // Afterwards the count moves exactly with the lines again (from wherever the loss left it).
    const auto before = s.decoder().count();
    const auto lost_before = s.lost();
    const auto paced = s.generate({"rate=2000", "+200"}, true);
    s.settle();
    CHECK(s.lost() == lost_before);
    CHECK(s.decoder().count() - before == paced.position);
  }
  SECTION("reader draining every millisecond while the generator writes as fast as it can") {
    Session s(by_label_and_names());
    const auto gen = s.generate({"rate=0", "+2000", "-400"}, true);
    s.settle();
    s.report("unpaced 2000 forward, 400 back, reader at 1 kHz", gen);
    const bool exact = s.lost() == 0 && s.decoder().count() == gen.position;
    std::printf("measured: unpaced burst %s\n", exact ? "counted exactly, no loss" : "reported as loss");
    CHECK((exact || s.lost() > 0));
    CHECK(s.encoder().levels() == gen.levels);
  }
}

TEST_CASE("both lines flipping unseen between two drains reach the decoder as an illegal transition") {
  Session s(by_label_and_names());
  // Both FIFOs are filled by chatter (16 edges each, lines back where they were), so the flip of both lines
  // that follows leaves no event at all: only the level check can see it.
  const auto gen = s.generate({"rate=0", "bounce:a=16", "bounce:b=16", "glitch"}, false);
  s.settle();
  s.report("chatter filling both FIFOs, then A and B flip", gen);
  CHECK(s.lost() > 0);
  CHECK(s.encoder().stats().resyncs >= 1);
  CHECK(s.decoder().illegal() >= 1);
  CHECK(s.encoder().levels() == gen.levels);

  const auto before = s.decoder().count();
  const auto lost_before = s.lost();
  const auto paced = s.generate({"rate=2000", "-300"}, true);
  s.settle();
  CHECK(s.lost() == lost_before);
  CHECK(s.decoder().count() - before == paced.position);
}

TEST_CASE("an edge that follows a lost one on the same line contradicts the level and is reported") {
  Session s(by_label_and_names());
  // 17 toggles of A: the FIFO keeps 16, the 17th (A's last move) is dropped.
  auto gen = s.generate({"rate=0", "bounce:a=17"}, false);
  s.drain();  // one drain: delivers the 16 (the full FIFO already counts as a loss), asks for a level check
  const auto lost_before = s.lost();
  // The next move of A arrives while the tracked level is still the wrong one.
  gen = s.generate({"rate=0", "bounce:a=1"}, false);
  s.settle();
  s.report("17 toggles of A, one drain, then this 1 toggle", gen);
  CHECK(lost_before > 0);
  CHECK(s.encoder().stats().impossible >= 1);
  CHECK(s.lost() > lost_before);  // the contradiction itself reaches the caller
  CHECK(s.encoder().levels() == gen.levels);
}

TEST_CASE("a line that is busy, missing or on no chip gives an error naming it, never an object") {
  GpioEncoderConfig c = by_label_and_names();
  c.line_b = LineRef::parse("enc-nope");
  auto r = GpioEncoder::open(c);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("line_b") != std::string::npos);
  CHECK(r.error().message.find("enc-nope") != std::string::npos);

  c = by_path_and_offsets();
  c.line_z = LineRef::offset(7);
  r = GpioEncoder::open(c);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("line_z (offset 7") != std::string::npos);

  Session holder(by_label_and_names());
  r = GpioEncoder::open(by_path_and_offsets());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("busy") != std::string::npos);
  CHECK(r.error().message.find("lever-gpio-sim-test") != std::string::npos);
}

namespace {

// The firmware core as a board runs it, on this encoder, with nothing else attached: what it counts is what a
// lever would.
struct NoForce {
  std::optional<lever::fw::ForceReading> latest() const { return std::nullopt; }
};
struct NoMotor {
  void command(const lever::fw::MotorCommand&) {}
  bool driver_fault() const { return false; }
};
struct NoCan {
  bool receive(lever::protocol::CanFrame&) { return false; }
  bool send(const lever::protocol::CanFrame&) { return true; }
};
using CoreHal = lever::fw::Ports<GpioEncoder, NoForce, NoMotor, NoCan>;

}  // namespace

TEST_CASE("the firmware core on this encoder counts every edge, the first one too: 4000 forward, 1500 back") {
  CoreHal hal{open_or_fail(by_label_and_names()), {}, {}, {}};
  lever::fw::HsiLever<CoreHal> lever(hal, lever::fw::LeverConfig{});
  lever::fw::Tick now = 1;
  const auto step = [&] { lever.step(now++); };
  const auto gen = run_generator({"rate=2000", "+4000", "-1500"}, step);
  for (int i = 0; i < 50; ++i) {  // stragglers and the last level check
    timespec ms{0, 1'000'000};
    ::nanosleep(&ms, nullptr);
    step();
  }
  REQUIRE(gen.position == 2500);
  CHECK(lever.decoder().lost_edges() == 0u);
  CHECK(lever.decoder().illegal_transitions() == 0u);
  CHECK(lever.decoder().counts() == 2500);
}

// Not a test: what rate the libgpiod path holds without loss, reader at 1 kHz as the firmware's loop. Run by
// hand in the guest (docs/board-encoder.md, "Throughput"); prints one JSON line per rate.
TEST_CASE("throughput: edges per second the reader holds with no loss", "[.throughput]") {
  const char* rates_env = std::getenv("LEVER_THROUGHPUT_RATES");
  std::vector<int> rates{2000, 4000, 8000, 12000, 16000, 24000, 32000, 48000};
  if (rates_env != nullptr && *rates_env != '\0') {
    rates.clear();
    std::istringstream in(rates_env);
    for (std::string item; std::getline(in, item, ',');) rates.push_back(std::stoi(item));
  }
  const int edges = std::getenv("LEVER_THROUGHPUT_EDGES") ? std::atoi(std::getenv("LEVER_THROUGHPUT_EDGES")) : 8000;
  const int repeat = std::getenv("LEVER_THROUGHPUT_REPEAT") ? std::atoi(std::getenv("LEVER_THROUGHPUT_REPEAT")) : 1;
  std::vector<int> runs;
  for (const int rate : rates)
    for (int i = 0; i < repeat; ++i) runs.push_back(rate);
  for (const int rate : runs) {
    Session s(by_label_and_names());
    const char* batch = std::getenv("LEVER_THROUGHPUT_BATCH");
    const auto gen = s.generate(
        {"rate=" + std::to_string(rate), std::string("batch=") + (batch ? batch : "1"), "+" + std::to_string(edges)},
        true);
    s.settle();
    const auto& st = s.encoder().stats();
    std::printf(
        "{\"asked_edges_per_s\": %d, \"batch\": %s, \"achieved_edges_per_s\": %.0f, \"edges\": %llu, \"delivered\": "
        "%llu, "
        "\"count\": %lld, \"exact\": %s, \"lost\": %llu, \"fifo_full\": %llu, \"impossible\": %llu, "
        "\"reordered\": %llu, \"drains\": %llu}\n",
        rate, batch ? batch : "1", gen.elapsed_s > 0 ? static_cast<double>(gen.edges) / gen.elapsed_s : 0.0,
        static_cast<unsigned long long>(gen.edges), static_cast<unsigned long long>(st.edges),
        static_cast<long long>(s.decoder().count()),
        s.decoder().count() == gen.position && s.lost() == 0 ? "true" : "false",
        static_cast<unsigned long long>(s.lost()), static_cast<unsigned long long>(st.fifo_full),
        static_cast<unsigned long long>(st.impossible), static_cast<unsigned long long>(st.reordered),
        static_cast<unsigned long long>(s.drains()));
    std::fflush(stdout);
  }
}
