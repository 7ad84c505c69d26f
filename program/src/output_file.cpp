#include "lever/program/output_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <stdexcept>

#include "lever/program/exit_codes.hpp"
#include "lever/program/text.hpp"

namespace lever::program {
namespace {

constexpr std::size_t kBufferBytes = 64 * 1024;

// Temporaries the signal handler removes. A handler may only touch lock-free atomics and call async-signal-safe
// functions (unlink, signal, raise): each slot holds a path written before its flag is set.
constexpr int kSlots = 16;
struct Slot {
  std::atomic<bool> used{false};
  std::atomic<bool> live{false};
  char path[4096] = {};
};
std::array<Slot, kSlots> g_slots;
constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP};

extern "C" void remove_temporaries(int sig) {
  for (auto& s : g_slots)
    if (s.live.load()) ::unlink(s.path);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// Installed once, for the signals whose action is still the default: a program that handles SIGINT itself
// (lever-hil serve stops and reports) keeps its handler and commits its files as it ends.
void install_handler() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (const int sig : kCleanupSignals) {
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL) continue;
      struct sigaction sa {};
      sa.sa_handler = remove_temporaries;
      sigemptyset(&sa.sa_mask);
      ::sigaction(sig, &sa, nullptr);
    }
  });
}

int claim_slot(const std::string& temp) {
  if (temp.size() >= sizeof(Slot::path)) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (g_slots[i].used.compare_exchange_strong(expected, true)) {
      std::memcpy(g_slots[i].path, temp.c_str(), temp.size() + 1);
      g_slots[i].live.store(true);
      return i;
    }
  }
  return -1;
}

void release_slot(int slot) {
  if (slot < 0) return;
  g_slots[slot].live.store(false);
  g_slots[slot].used.store(false);
}

const char* kind_of(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISLNK(m)) return "a symbolic link";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISFIFO(m)) return "a FIFO";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

}  // namespace

OutputFile::OutputFile(std::string path, std::string what, const std::vector<std::string>& inputs)
    : path_(std::move(path)), what_(std::move(what)) {
  const std::string shown = printable(path_, 200);
  if (path_.empty()) throw BadInput(fmt::format("{}: an empty path", what_));
  if (path_ == "-") {
    fd_ = 1;
    buffer_.reserve(kBufferBytes);
    return;
  }
  struct stat target {};
  if (::lstat(path_.c_str(), &target) == 0) {
    if (S_ISLNK(target.st_mode))
      throw BadInput(
          fmt::format("{} {} is a symbolic link; name the file it points to (the file would replace "
                      "the link)",
                      what_, shown));
    if (!S_ISREG(target.st_mode))
      throw BadInput(fmt::format("{} {} is {}; only a regular file (or '-' for stdout) is written", what_, shown,
                                 kind_of(target.st_mode)));
    for (const auto& input : inputs) {
      struct stat in {};
      if (input != "-" && ::stat(input.c_str(), &in) == 0 && in.st_dev == target.st_dev && in.st_ino == target.st_ino)
        throw BadInput(
            fmt::format("{} {} is the input file {}; write to another file", what_, shown, printable(input, 200)));
    }
  } else if (errno != ENOENT) {
    throw BadInput(fmt::format("{} {}: {}", what_, shown, std::strerror(errno)));
  }
  const std::filesystem::path p(path_);
  if (!p.has_filename() || path_.back() == '/')
    throw BadInput(fmt::format("{} {} names a directory, not a file", what_, shown));
  const std::string dir = p.has_parent_path() ? p.parent_path().string() : ".";
  struct stat d {};
  if (::stat(dir.c_str(), &d) != 0)
    throw BadInput(fmt::format("{} {}: the directory {} {}", what_, shown, printable(dir, 200),
                               errno == ENOENT ? "does not exist" : std::strerror(errno)));
  if (!S_ISDIR(d.st_mode))
    throw BadInput(fmt::format("{} {}: {} is not a directory", what_, shown, printable(dir, 200)));

  // fmt rather than operator+: GCC 12 reports a false -Wrestrict on that concatenation at -O3 (bug 105651).
  temp_ = fmt::format("{}/.{}.XXXXXX", dir, p.filename().string());
  install_handler();
  // The slot is claimed before the file exists: a signal between mkstemp and the claim would leave it behind.
  sigset_t all, old;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, &old);
  fd_ = ::mkstemp(temp_.data());
  const int error = errno;
  if (fd_ >= 0) slot_ = claim_slot(temp_);
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
  if (fd_ < 0) throw std::runtime_error(fmt::format("cannot write {} {}: {}", what_, shown, std::strerror(error)));
  buffer_.reserve(kBufferBytes);
}

OutputFile::~OutputFile() {
  if (fd_ > 1) ::close(fd_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
  release_slot(slot_);
}

void OutputFile::fail(const char* doing, int error) {
  throw std::runtime_error(
      fmt::format("cannot {} {} {}: {}", doing, what_, printable(path_, 200), std::strerror(error)));
}

void OutputFile::flush() {
  const char* data = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write", errno);
    }
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  buffer_.clear();
}

void OutputFile::write(std::string_view data) {
  if (buffer_.size() + data.size() > kBufferBytes) flush();
  if (data.size() >= kBufferBytes) {
    buffer_.assign(data.begin(), data.end());
    flush();
    return;
  }
  buffer_.insert(buffer_.end(), data.begin(), data.end());
}

void OutputFile::commit() {
  flush();
  if (fd_ == 1) {
    committed_ = true;
    return;
  }
  // mkstemp creates 0600; a result file should be as readable as any other the user writes.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  if (::fchmod(fd_, 0666 & ~mask) != 0) fail("write", errno);
  if (::fsync(fd_) != 0) fail("write", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("write", errno);
  // The target may have become something else while the program ran; the rename would replace it.
  struct stat target {};
  if (::lstat(path_.c_str(), &target) == 0 && !S_ISREG(target.st_mode))
    throw BadInput(fmt::format("{} {} became {} while the program ran; not replaced", what_, printable(path_, 200),
                               kind_of(target.st_mode)));
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) fail("write", errno);
  committed_ = true;
  release_slot(slot_);
  slot_ = -1;
}

void OutputFile::write_all(const std::string& path, std::string_view content, const std::string& what,
                           const std::vector<std::string>& inputs) {
  OutputFile f(path, what, inputs);
  f.write(content);
  f.commit();
}

void check_input_path(const std::string& path, const std::string& what) {
  if (path == "-") return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw BadInput(fmt::format("{} {}: cannot read: {}", what, printable(path, 200), std::strerror(errno)));
  if (S_ISDIR(st.st_mode)) throw BadInput(fmt::format("{} {} is a directory", what, printable(path, 200)));
}

}  // namespace lever::program
