// The candump recorder: the exact `candump -L` line, every accepted frame exactly once and in order, drops counted
// and never blocking, rotation into whole-line files, draining on destruction, write errors counted, and the files
// read by can-utils' own log2asc (and canplayer, where the kernel has CAN sockets).
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "candump_recorder.hpp"
#include "skip.hpp"

namespace fs = std::filesystem;
using lever::bridge::CandumpRecorder;
using lever::bridge::RecorderConfig;
using lever::protocol::CanFrame;
using namespace std::chrono_literals;

// ---- Allocation counter: proves record() never reaches the heap ----
// Replaces the global operator new and delete for this test program, forwarding to malloc and free as the
// defaults do, and counts the calling thread's allocations only (the writer thread's do not disturb the count).
// Every non-aligned form is replaced, so that no pointer from a sanitizer's own operator new reaches our free
// (ASan would report an alloc-dealloc mismatch); the aligned forms keep the library's (or ASan's) pair.
// Not inlined: GCC 12 would otherwise see malloc's pointer reach free through new/delete and warn
// (-Wmismatched-new-delete).
namespace {
thread_local std::size_t t_allocations = 0;

[[gnu::noinline]] void* counted_malloc(std::size_t size) noexcept {
  ++t_allocations;
  return std::malloc(size == 0 ? 1 : size);
}
}  // namespace

[[gnu::noinline]] void* operator new(std::size_t size) {
  if (void* p = counted_malloc(size)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t size) {
  if (void* p = counted_malloc(size)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return counted_malloc(size); }
[[gnu::noinline]] void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return counted_malloc(size);
}
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace {

constexpr std::int64_t kEpochUs = 1'700'000'000'000'000;  // 2023-11-14T22:13:20Z

class RecorderDir {
 public:
  RecorderDir() {
    std::string pattern = (fs::temp_directory_path() / "lever-recorder-test-XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
  }
  ~RecorderDir() { fs::remove_all(path_); }
  RecorderDir(const RecorderDir&) = delete;
  RecorderDir& operator=(const RecorderDir&) = delete;
  fs::path file(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

CanFrame frame(std::uint32_t id, std::vector<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.dlc = static_cast<std::uint8_t>(bytes.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) f.data[i] = bytes[i];
  return f;
}

// Frame number i of a sequence: its id, dlc and data all derive from i, so a line tells which frame it is.
CanFrame numbered_frame(std::uint64_t i) {
  CanFrame f;
  f.id = static_cast<std::uint32_t>(i % 0x800);
  f.dlc = static_cast<std::uint8_t>(i % 9);
  for (std::size_t b = 0; b < 8; ++b) f.data[b] = static_cast<std::uint8_t>(i >> (8 * (b % 4)));
  return f;
}
std::int64_t numbered_time(std::uint64_t i) { return kEpochUs + static_cast<std::int64_t>(i) * 50; }  // 20 kHz

// A second implementation of the line, with printf as can-utils does it: "(%010ld.%06ld) %s %03X#" + "%02X".
std::string reference_line(std::int64_t us, const std::string& iface, const CanFrame& f) {
  char text[128];
  int n = std::snprintf(text, sizeof text, "(%010lld.%06lld) %s %03X#", static_cast<long long>(us / 1'000'000),
                        static_cast<long long>(us % 1'000'000), iface.c_str(), static_cast<unsigned>(f.id));
  for (std::size_t i = 0; i < f.dlc; ++i)
    n += std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n), "%02X", f.data[i]);
  return std::string(text, static_cast<std::size_t>(n));
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The file's lines; fails the test unless it is empty or ends with a newline (whole lines only).
std::vector<std::string> read_lines(const fs::path& path) {
  const std::string text = read_file(path);
  if (!text.empty()) REQUIRE(text.back() == '\n');
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

RecorderConfig config_for(const fs::path& path) {
  RecorderConfig config;
  config.path = path;
  return config;
}

// A writer that only wakes for flush() and the destructor: the ring fills as if the disk had stalled.
RecorderConfig stalled_config(const fs::path& path, std::size_t capacity) {
  RecorderConfig config = config_for(path);
  config.queue_capacity = capacity;
  config.poll_interval = 1h;
  return config;
}

bool tool_installed(const std::string& name) {
  return std::system(("command -v " + name + " >/dev/null 2>&1").c_str()) == 0;
}

int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST_CASE("recorder: the exact candump -L line", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("format.log");
  std::vector<std::string> expected;
  {
    CandumpRecorder recorder(config_for(path));
    const auto add = [&](std::int64_t us, const char* iface, const CanFrame& f, const char* line) {
      REQUIRE(recorder.record(us, iface, f));
      expected.push_back(line);
    };
    add(kEpochUs + 123'456, "vcan0", frame(0x123, {0xDE, 0xAD, 0xBE, 0xEF}), "(1700000000.123456) vcan0 123#DEADBEEF");
    // dlc 0..8, ids 0x000 and 0x7FF, uppercase hex, no separators, nothing after '#' for dlc 0.
    add(kEpochUs, "vcan0", frame(0x000, {}), "(1700000000.000000) vcan0 000#");
    add(kEpochUs, "vcan0", frame(0x7FF, {}), "(1700000000.000000) vcan0 7FF#");
    add(kEpochUs, "vcan0", frame(0x7FF, {0xab}), "(1700000000.000000) vcan0 7FF#AB");
    add(kEpochUs, "vcan0", frame(0x000, {0x00, 0x0f}), "(1700000000.000000) vcan0 000#000F");
    add(kEpochUs, "vcan0", frame(0x00A, {1, 2, 3}), "(1700000000.000000) vcan0 00A#010203");
    add(kEpochUs, "vcan0", frame(0x0B0, {1, 2, 3, 4}), "(1700000000.000000) vcan0 0B0#01020304");
    add(kEpochUs, "vcan0", frame(0x7FF, {0xc0, 0xff, 0xee, 0x12, 0x34}), "(1700000000.000000) vcan0 7FF#C0FFEE1234");
    add(kEpochUs, "vcan0", frame(0x001, {0, 0, 0, 0, 0, 0}), "(1700000000.000000) vcan0 001#000000000000");
    add(kEpochUs, "vcan0", frame(0x7FF, {0xfe, 0xdc, 0xba, 0x98, 0x76, 0x54, 0x32}),
        "(1700000000.000000) vcan0 7FF#FEDCBA98765432");
    add(kEpochUs, "vcan0", frame(0x000, {0x01, 0x23, 0x45, 0x67, 0x89, 0xab, 0xcd, 0xef}),
        "(1700000000.000000) vcan0 000#0123456789ABCDEF");
    // Microseconds keep their leading zeros (the tools read them as an integer count of microseconds).
    add(kEpochUs + 1, "vcan0", frame(0x100, {}), "(1700000000.000001) vcan0 100#");
    add(kEpochUs + 10, "vcan0", frame(0x100, {}), "(1700000000.000010) vcan0 100#");
    add(kEpochUs + 999, "vcan0", frame(0x100, {}), "(1700000000.000999) vcan0 100#");
    add(kEpochUs + 99'999, "vcan0", frame(0x100, {}), "(1700000000.099999) vcan0 100#");
    add(kEpochUs + 999'999, "vcan0", frame(0x100, {}), "(1700000000.999999) vcan0 100#");
    // Seconds are zero-padded to 10 digits, as candump's "%010ld" does.
    add(0, "vcan0", frame(0x100, {}), "(0000000000.000000) vcan0 100#");
    add(1'500'042, "vcan0", frame(0x100, {}), "(0000000001.500042) vcan0 100#");
    // Each record carries its own interface name, up to 15 characters.
    add(kEpochUs, "can1", frame(0x042, {0x42}), "(1700000000.000000) can1 042#42");
    add(kEpochUs, "udp-site-b", frame(0x042, {0x42}), "(1700000000.000000) udp-site-b 042#42");
    add(kEpochUs, "abcdefghijklmno", frame(0x042, {0x42}), "(1700000000.000000) abcdefghijklmno 042#42");
  }
  CHECK(read_lines(path) == expected);
  // And the reference printf implementation agrees on a sample.
  CHECK(reference_line(kEpochUs + 7, "vcan0", frame(0x7FF, {0xab})) == "(1700000000.000007) vcan0 7FF#AB");
}

TEST_CASE("recorder: frames that cannot be written as a candump line are rejected and counted", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("rejects.log");
  CandumpRecorder recorder(config_for(path));
  CanFrame too_long = frame(0x100, {});
  too_long.dlc = 9;
  CHECK_FALSE(recorder.record(kEpochUs, "vcan0", frame(0x800, {1})));  // not an 11-bit id
  CHECK_FALSE(recorder.record(kEpochUs, "vcan0", too_long));
  CHECK_FALSE(recorder.record(-1, "vcan0", frame(0x100, {})));
  CHECK_FALSE(recorder.record(kEpochUs, "", frame(0x100, {})));
  CHECK_FALSE(recorder.record(kEpochUs, "abcdefghijklmnop", frame(0x100, {})));  // 16 > IFNAMSIZ - 1
  CHECK_FALSE(recorder.record(kEpochUs, "vcan 0", frame(0x100, {})));            // would split the line
  CHECK_FALSE(recorder.record(kEpochUs, "vcan\n0", frame(0x100, {})));
  CHECK_FALSE(recorder.record(kEpochUs, "vcan:0", frame(0x100, {})));  // the kernel refuses ':' and '/'
  CHECK_FALSE(recorder.record(kEpochUs, "a/b", frame(0x100, {})));
  CHECK(recorder.record(kEpochUs, "vcan0", frame(0x100, {})));
  recorder.flush();
  const auto s = recorder.stats();
  CHECK(s.rejected == 9);
  CHECK(s.recorded == 1);
  CHECK(s.dropped_queue_full == 0);
  CHECK(read_lines(path) == std::vector<std::string>{"(1700000000.000000) vcan0 100#"});
}

TEST_CASE("recorder: record() does not allocate", "[recorder]") {
  RecorderDir dir;
  RecorderConfig config = config_for(dir.file("alloc.log"));
  config.queue_capacity = 64;  // fills, so the drop path is measured too
  CandumpRecorder recorder(config);
  const std::string iface = "vcan0";
  const std::size_t before = t_allocations;
  for (std::uint64_t i = 0; i < 10'000; ++i) recorder.record(numbered_time(i), iface, numbered_frame(i));
  recorder.record(kEpochUs, "abcdefghijklmnopq", numbered_frame(1));  // rejected
  CHECK(t_allocations == before);
}

TEST_CASE("recorder: 100k frames from one thread arrive exactly once and in order", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("order.log");
  constexpr std::uint64_t kFrames = 100'000;
  RecorderConfig config = config_for(path);
  config.queue_capacity = 1000;  // rounded up to 1024: the ring wraps ~100 times and fills now and then
  config.poll_interval = 1ms;
  std::uint64_t attempts = 0;
  {
    CandumpRecorder recorder(config);
    CHECK(recorder.capacity() == 1024);
    for (std::uint64_t i = 0; i < kFrames; ++i) {
      // The test retries a dropped frame, so that every frame is accepted once; the bridge would not.
      while (++attempts, !recorder.record(numbered_time(i), i % 3 == 0 ? "udp0" : "vcan0", numbered_frame(i)))
        std::this_thread::yield();
    }
    recorder.flush();
    const auto s = recorder.stats();
    CHECK(s.recorded == kFrames);
    CHECK(s.recorded + s.dropped_queue_full == attempts);
    CHECK(s.written == kFrames);
    CHECK(s.lost == 0);
    CHECK(s.write_errors == 0);
    CHECK(s.bytes_written == fs::file_size(path));
  }
  const auto lines = read_lines(path);
  REQUIRE(lines.size() == kFrames);
  std::uint64_t mismatches = 0;
  for (std::uint64_t i = 0; i < kFrames; ++i) {
    if (lines[i] != reference_line(numbered_time(i), i % 3 == 0 ? "udp0" : "vcan0", numbered_frame(i))) {
      if (++mismatches < 5) UNSCOPED_INFO("line " << i << ": " << lines[i]);
    }
  }
  CHECK(mismatches == 0);
}

TEST_CASE("recorder: a full ring drops and counts, and never blocks the producer", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("full.log");
  constexpr std::uint64_t kOffered = 1000;
  CandumpRecorder recorder(stalled_config(path, 5));
  CHECK(recorder.capacity() == 8);  // 5 rounded up to a power of two
  std::vector<std::uint64_t> accepted;
  const auto start = std::chrono::steady_clock::now();
  for (std::uint64_t i = 0; i < kOffered; ++i) {
    if (recorder.record(numbered_time(i), "vcan0", numbered_frame(i))) accepted.push_back(i);
  }
  const auto elapsed = std::chrono::steady_clock::now() - start;
  CHECK(elapsed < 100ms);  // 1000 calls; a blocking producer would wait for the writer's hour-long poll

  const auto s = recorder.stats();
  CHECK(s.recorded == accepted.size());
  CHECK(s.dropped_queue_full + s.recorded == kOffered);
  // The writer drained at most once (when it started): at most two ring-fulls got in.
  CHECK(s.recorded >= 8);
  CHECK(s.recorded <= 16);
  CHECK(s.dropped_queue_full >= kOffered - 16);

  recorder.flush();  // wakes the stalled writer
  std::vector<std::string> expected;
  for (const auto i : accepted) expected.push_back(reference_line(numbered_time(i), "vcan0", numbered_frame(i)));
  CHECK(read_lines(path) == expected);

  // Room again after the drain.
  CHECK(recorder.record(kEpochUs, "vcan0", frame(0x1, {})));
}

TEST_CASE("recorder: capacity 1 and a burst", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("one.log");
  CandumpRecorder recorder(stalled_config(path, 1));
  std::uint64_t accepted = 0;
  for (std::uint64_t i = 0; i < 100; ++i) accepted += recorder.record(numbered_time(i), "vcan0", numbered_frame(i));
  const auto s = recorder.stats();
  CHECK(s.recorded == accepted);
  CHECK(s.recorded + s.dropped_queue_full == 100);
  CHECK(s.recorded <= 2);
  recorder.flush();
  CHECK(read_lines(path).size() == accepted);
}

TEST_CASE("recorder: flush() puts everything accepted so far on disk", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("flush.log");
  CandumpRecorder recorder(stalled_config(path, 1024));
  recorder.flush();  // nothing queued: returns at once
  for (std::uint64_t i = 0; i < 100; ++i) REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
  recorder.flush();
  CHECK(read_lines(path).size() == 100);
  for (std::uint64_t i = 100; i < 150; ++i) REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
  recorder.flush();
  const auto lines = read_lines(path);
  REQUIRE(lines.size() == 150);
  CHECK(lines.back() == reference_line(numbered_time(149), "vcan0", numbered_frame(149)));
  CHECK(recorder.stats().written == 150);
}

TEST_CASE("recorder: flush() from another thread while the relay thread records", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("concurrent.log");
  constexpr std::uint64_t kFrames = 20'000;
  RecorderConfig config = config_for(path);
  config.queue_capacity = 256;
  std::atomic<bool> done{false};
  {
    CandumpRecorder recorder(config);
    std::thread relay([&] {
      for (std::uint64_t i = 0; i < kFrames; ++i) {
        while (!recorder.record(numbered_time(i), "vcan0", numbered_frame(i))) std::this_thread::yield();
      }
      done = true;
    });
    int flushes = 0;
    while (!done) {
      recorder.flush();
      (void)recorder.stats();
      ++flushes;
    }
    relay.join();
    recorder.flush();
    CHECK(flushes > 0);
    CHECK(recorder.stats().written == kFrames);
  }
  const auto lines = read_lines(path);
  REQUIRE(lines.size() == kFrames);
  CHECK(lines.front() == reference_line(numbered_time(0), "vcan0", numbered_frame(0)));
  CHECK(lines.back() == reference_line(numbered_time(kFrames - 1), "vcan0", numbered_frame(kFrames - 1)));
}

TEST_CASE("recorder: the destructor drains everything that was accepted", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("drain.log");
  constexpr std::uint64_t kFrames = 10'000;
  {
    // The writer is asleep for an hour: only the destructor's stop request can get these frames out.
    CandumpRecorder recorder(stalled_config(path, 16384));
    for (std::uint64_t i = 0; i < kFrames; ++i) REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
  }
  const auto lines = read_lines(path);
  REQUIRE(lines.size() == kFrames);
  for (std::uint64_t i = 0; i < kFrames; i += 997)
    CHECK(lines[i] == reference_line(numbered_time(i), "vcan0", numbered_frame(i)));
  CHECK(lines.back() == reference_line(numbered_time(kFrames - 1), "vcan0", numbered_frame(kFrames - 1)));
}

namespace {

// The recording's files, oldest first: path.N ... path.1, path.
std::vector<fs::path> rotated_files(const fs::path& path, int keep_files) {
  std::vector<fs::path> files;
  for (int n = keep_files + 5; n >= 1; --n) {
    const fs::path numbered = path.string() + "." + std::to_string(n);
    if (fs::exists(numbered)) files.push_back(numbered);
  }
  if (fs::exists(path)) files.push_back(path);
  return files;
}

}  // namespace

TEST_CASE("recorder: rotation keeps whole lines, every frame once, at most keep_files + 1 files", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("rotate.log");
  constexpr std::uint64_t kRotateBytes = 1000;
  constexpr std::uint64_t kFrames = 600;

  SECTION("all files kept: together they hold every frame exactly once, in order") {
    constexpr int kKeep = 100;
    RecorderConfig config = config_for(path);
    config.rotate_bytes = kRotateBytes;
    config.keep_files = kKeep;
    std::uint64_t rotations = 0;
    {
      CandumpRecorder recorder(config);
      for (std::uint64_t i = 0; i < kFrames; ++i) {
        REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
        if (i % 100 == 0) recorder.flush();  // rotation also between flushes and drains
      }
      recorder.flush();
      rotations = recorder.stats().rotations;
      CHECK(recorder.stats().written == kFrames);
    }
    const auto files = rotated_files(path, kKeep);
    CHECK(rotations >= 10);  // ~600 lines of 30-45 bytes into 1000-byte files
    CHECK(files.size() == rotations + 1);
    std::uint64_t next = 0;
    for (const auto& file : files) {
      INFO(file);
      const auto size = fs::file_size(file);
      CHECK(size > 0);
      CHECK(size <= kRotateBytes);
      for (const auto& line : read_lines(file)) {  // whole lines, each file on its own
        REQUIRE(next < kFrames);
        CHECK(line == reference_line(numbered_time(next), "vcan0", numbered_frame(next)));
        ++next;
      }
    }
    CHECK(next == kFrames);
  }

  SECTION("keep_files = 3: the newest frames, in at most 4 files") {
    constexpr int kKeep = 3;
    RecorderConfig config = config_for(path);
    config.rotate_bytes = kRotateBytes;
    config.keep_files = kKeep;
    {
      CandumpRecorder recorder(config);
      for (std::uint64_t i = 0; i < kFrames; ++i)
        REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
    }
    const auto files = rotated_files(path, kKeep);
    CHECK(files.size() == kKeep + 1);
    CHECK_FALSE(fs::exists(path.string() + ".4"));
    std::vector<std::string> lines;
    for (const auto& file : files) {
      CHECK(fs::file_size(file) <= kRotateBytes);
      for (auto& line : read_lines(file)) lines.push_back(std::move(line));
    }
    // A contiguous run ending with the last frame.
    REQUIRE(!lines.empty());
    REQUIRE(lines.size() < kFrames);
    const std::uint64_t first = kFrames - lines.size();
    for (std::uint64_t k = 0; k < lines.size(); ++k)
      CHECK(lines[k] == reference_line(numbered_time(first + k), "vcan0", numbered_frame(first + k)));
  }
}

TEST_CASE("recorder: a line longer than rotate_bytes still goes into a file of its own", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("tiny.log");
  RecorderConfig config = config_for(path);
  config.rotate_bytes = 10;
  config.keep_files = 10;
  {
    CandumpRecorder recorder(config);
    for (std::uint64_t i = 0; i < 3; ++i) REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
  }
  CHECK(read_lines(path.string() + ".2").size() == 1);
  CHECK(read_lines(path.string() + ".1").size() == 1);
  CHECK(read_lines(path).size() == 1);
}

TEST_CASE("recorder: an existing recording is moved aside, not truncated", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("restart.log");
  const std::string old_line = "(1600000000.000000) vcan0 123#\n";
  std::ofstream(path) << old_line;

  SECTION("to path.1") {
    { CandumpRecorder recorder(config_for(path)); }
    CHECK(read_file(path.string() + ".1") == old_line);
    CHECK(read_file(path).empty());
  }
  SECTION("or replaced with keep_files = 0") {
    RecorderConfig config = config_for(path);
    config.keep_files = 0;
    {
      CandumpRecorder recorder(config);
      REQUIRE(recorder.record(kEpochUs, "vcan0", frame(0x7, {})));
    }
    CHECK_FALSE(fs::exists(path.string() + ".1"));
    CHECK(read_file(path) == "(1700000000.000000) vcan0 007#\n");
  }
}

TEST_CASE("recorder: a file that cannot be created is refused with its name", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("no-such-dir") / "x.log";
  try {
    CandumpRecorder recorder(config_for(path));
    FAIL("no exception");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains(path.string()));
    CHECK_THAT(what, Catch::Contains("No such file or directory"));
  }
  RecorderConfig bad = config_for(dir.file("x.log"));
  bad.queue_capacity = 0;
  CHECK_THROWS_AS(CandumpRecorder(bad), std::invalid_argument);
  bad = config_for(dir.file("x.log"));
  bad.keep_files = -1;
  CHECK_THROWS_AS(CandumpRecorder(bad), std::invalid_argument);
  bad.keep_files = 1001;
  CHECK_THROWS_AS(CandumpRecorder(bad), std::invalid_argument);
}

TEST_CASE("recorder: a full disk is counted, not thrown, and the recorder goes on", "[recorder]") {
  // /dev/full fails every write with ENOSPC.
  if (::access("/dev/full", W_OK) != 0) LEVER_SKIP("no writable /dev/full on this machine");
  RecorderConfig config = config_for("/dev/full");
  CandumpRecorder recorder(config);
  for (std::uint64_t i = 0; i < 10; ++i) REQUIRE(recorder.record(numbered_time(i), "vcan0", numbered_frame(i)));
  recorder.flush();
  auto s = recorder.stats();
  CHECK(s.recorded == 10);
  CHECK(s.written == 0);
  CHECK(s.lost == 10);
  CHECK(s.write_errors >= 1);
  CHECK_THAT(recorder.last_error(), Catch::Contains("/dev/full") && Catch::Contains("No space left on device"));
  CHECK(recorder.record(numbered_time(10), "vcan0", numbered_frame(10)));
  recorder.flush();
  s = recorder.stats();
  CHECK(s.lost == 11);
  CHECK(s.recorded == s.written + s.lost);
}

TEST_CASE("recorder: can-utils' log2asc converts the log, one line per frame", "[recorder][can-utils]") {
  if (!tool_installed("log2asc")) LEVER_SKIP("log2asc (can-utils, in scripts/setup) is not installed");
  RecorderDir dir;
  const auto log = dir.file("both.log");
  const auto asc = dir.file("both.asc");
  constexpr std::uint64_t kFrames = 900;
  {
    CandumpRecorder recorder(config_for(log));
    for (std::uint64_t i = 0; i < kFrames; ++i)
      REQUIRE(recorder.record(numbered_time(i), i % 2 == 0 ? "vcan0" : "udp0", numbered_frame(i)));
  }
  // log2asc converts only the interfaces named on its command line, as channels 1, 2, ...
  const std::string command = "log2asc -I '" + log.string() + "' -O '" + asc.string() + "' vcan0 udp0 2>&1";
  REQUIRE(run(command) == 0);
  const auto lines = read_lines(asc);
  // A header (date, base, "no internal events logged"), then a line per frame:
  //   "   0.000050 2  1               Rx   d 1 01"
  std::vector<std::string> frames;
  for (const auto& line : lines) {
    if (line.find(" Rx ") != std::string::npos) frames.push_back(line);
  }
  REQUIRE(frames.size() == kFrames);
  for (std::uint64_t i = 0; i < kFrames; i += 7) {
    const CanFrame f = numbered_frame(i);
    std::istringstream in(frames[i]);
    std::string time, channel, id, dir_field, kind;
    unsigned dlc = 99;
    in >> time >> channel >> id >> dir_field >> kind >> std::hex >> dlc;
    INFO(frames[i]);
    CHECK(channel == (i % 2 == 0 ? "1" : "2"));
    CHECK(std::stoul(id, nullptr, 16) == f.id);
    CHECK(kind == "d");
    CHECK(dlc == f.dlc);
    const auto us = numbered_time(i) - numbered_time(0);
    char expected_time[32];
    std::snprintf(expected_time, sizeof expected_time, "%lld.%06lld", static_cast<long long>(us / 1'000'000),
                  static_cast<long long>(us % 1'000'000));
    CHECK(time == expected_time);
    for (std::size_t b = 0; b < f.dlc; ++b) {
      unsigned byte = 999;
      in >> std::hex >> byte;
      CHECK(byte == f.data[b]);
    }
  }
}

TEST_CASE("recorder: canplayer reads the log (where the kernel has CAN sockets)", "[recorder][can-utils]") {
  if (!tool_installed("canplayer")) LEVER_SKIP("canplayer (can-utils, in scripts/setup) is not installed");
  RecorderDir dir;
  const auto log = dir.file("replay.log");
  const auto out = dir.file("replay.out");
  std::vector<std::string> vcan0_lines;
  {
    CandumpRecorder recorder(config_for(log));
    for (std::uint64_t i = 0; i < 100; ++i) {
      const char* iface = i % 4 == 0 ? "udp0" : "vcan0";
      REQUIRE(recorder.record(numbered_time(i), iface, numbered_frame(i)));
      if (i % 4 != 0) vcan0_lines.push_back(reference_line(numbered_time(i), "vcan0", numbered_frame(i)));
    }
  }
  // "stdout=vcan0": print the lines logged for vcan0 as they are, and (assignments given) skip the others.
  // canplayer opens a CAN socket even so; without one (no AF_CAN in this kernel or container) it cannot run.
  const int status = run("canplayer -t -I '" + log.string() + "' stdout=vcan0 > '" + out.string() + "' 2>&1");
  const std::string output = read_file(out);
  if (status != 0 && output.find("socket") != std::string::npos)
    LEVER_SKIP("canplayer cannot open a CAN socket on this machine (no AF_CAN in its kernel or container): " + output);
  REQUIRE(status == 0);
  std::vector<std::string> printed;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);) printed.push_back(line);
  CHECK(printed == vcan0_lines);
}

TEST_CASE("recorder: two rings, one per relay thread, come out merged by time stamp", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("rings.log");
  RecorderConfig config = stalled_config(path, 64);
  config.rings = 2;
  CandumpRecorder recorder(config);
  // Ring 0 gets the even frames, ring 1 the odd ones, each in its own order but the rings filled one after the
  // other: only the merge puts them back in time order.
  for (std::uint64_t i = 0; i < 40; i += 2) REQUIRE(recorder.record(0, numbered_time(i), "vcan0", numbered_frame(i)));
  for (std::uint64_t i = 1; i < 40; i += 2) REQUIRE(recorder.record(1, numbered_time(i), "udp0", numbered_frame(i)));
  CHECK_FALSE(recorder.record(2, numbered_time(0), "vcan0", numbered_frame(0)));  // no such ring
  recorder.flush();
  const auto lines = read_lines(path);
  REQUIRE(lines.size() == 40);
  for (std::uint64_t i = 0; i < 40; ++i) {
    CAPTURE(i);
    CHECK(lines[i] == reference_line(numbered_time(i), i % 2 ? "udp0" : "vcan0", numbered_frame(i)));
  }
  const auto s = recorder.stats();
  CHECK(s.recorded == 40);
  CHECK(s.rejected == 1);
  CHECK(s.written == 40);
}

TEST_CASE("recorder: two producer threads at once, the writer polling", "[recorder]") {
  RecorderDir dir;
  const auto path = dir.file("threads.log");
  RecorderConfig config = config_for(path);
  config.rings = 2;
  config.queue_capacity = 256;
  constexpr std::uint64_t kFrames = 4000;
  {
    CandumpRecorder recorder(config);
    // Each thread stamps its frames with the wall clock as the relay does, just before record().
    const auto produce = [&](std::size_t ring) {
      for (std::uint64_t i = ring; i < kFrames; i += 2) {
        timespec ts{};
        ::clock_gettime(CLOCK_REALTIME, &ts);
        const std::int64_t now = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
        while (!recorder.record(ring, now, ring ? "udp0" : "vcan0", numbered_frame(i))) std::this_thread::yield();
      }
    };
    std::thread a(produce, 0), b(produce, 1);
    a.join();
    b.join();
    recorder.flush();
    CHECK(recorder.stats().written == kFrames);
  }
  const auto lines = read_lines(path);
  REQUIRE(lines.size() == kFrames);
  // Every frame once; per ring in order (a ring is a queue). The interleaving of the rings is by time stamp, which
  // a loaded machine can break by stalling a producer between its stamp and record() (the header says so), so
  // only the per-ring order is asserted.
  std::uint64_t next[2] = {0, 1};
  for (const auto& line : lines) {
    const std::size_t ring = line.find(" udp0 ") != std::string::npos ? 1 : 0;
    const auto expected_tail = reference_line(0, ring ? "udp0" : "vcan0", numbered_frame(next[ring]));
    CHECK(line.substr(line.find(')')) == expected_tail.substr(expected_tail.find(')')));
    next[ring] += 2;
  }
  CHECK(next[0] == kFrames);
  CHECK(next[1] == kFrames + 1);
}
