#include "status_reader.hpp"

#include <poll.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <utility>

#include "status_line.hpp"

namespace lever::view {

StatusReader::StatusReader(board::UniqueFd fd, std::size_t source, LiveMonitor& live)
    : fd_(std::move(fd)),
      source_(source),
      live_(live),
      thread_([this](std::stop_token stop) { run(std::move(stop)); }) {}

void StatusReader::on_line(const std::string& line) {
  const StatusLine parsed = parse_status_line(line);
  if (std::holds_alternative<std::monostate>(parsed)) return;
  const std::lock_guard lock(live_.mutex);
  live_.monitor.on_status(parsed, source_, realtime_us());
}

void StatusReader::run(std::stop_token stop) {
  std::array<char, 4096> buffer;
  std::string line;
  bool overlong = false;
  while (!stop.stop_requested()) {
    pollfd pfd{fd_.get(), POLLIN, 0};
    if (poll(&pfd, 1, 200) <= 0) continue;
    const ssize_t n = ::read(fd_.get(), buffer.data(), buffer.size());
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
    if (n <= 0) {
      // The end of what is there (a file not yet grown, a FIFO or pipe whose writer left): follow it, as tail -f.
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      continue;
    }
    for (ssize_t i = 0; i < n; ++i) {
      const char c = buffer[static_cast<std::size_t>(i)];
      if (c == '\n') {
        if (!overlong) on_line(line);
        line.clear();
        overlong = false;
      } else if (line.size() < kMaxLine) {
        line += c;
      } else {
        overlong = true;
      }
    }
  }
}

}  // namespace lever::view
