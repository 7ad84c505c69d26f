#pragma once
// A thread that follows one input of status lines (a file as it grows, a FIFO, or stdin) and hands every line
// the monitor understands to it. It never blocks for long, so it stops when asked.
#include <cstddef>
#include <stop_token>
#include <string>
#include <thread>

#include "lever/board/unique_fd.hpp"
#include "live_monitor.hpp"

namespace lever::view {

class StatusReader {
 public:
  // The longest line kept: a longer one is not a status line and is skipped to its end.
  static constexpr std::size_t kMaxLine = 64 * 1024;

  // `fd` open for reading; `source` numbers the input in the monitor.
  StatusReader(board::UniqueFd fd, std::size_t source, LiveMonitor& live);
  StatusReader(const StatusReader&) = delete;
  StatusReader& operator=(const StatusReader&) = delete;

 private:
  void run(std::stop_token stop);
  void on_line(const std::string& line);

  board::UniqueFd fd_;
  std::size_t source_;
  LiveMonitor& live_;
  std::jthread thread_;
};

}  // namespace lever::view
