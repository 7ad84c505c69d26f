#pragma once
// The thread that reads every frame of the CAN interface and feeds the monitor: it does nothing else, so the
// kernel's receive queue is emptied however long a screen takes to draw.
#include <stop_token>
#include <thread>

#include "lever/board/socketcan.hpp"
#include "live_monitor.hpp"

namespace lever::view {

class CanReader {
 public:
  CanReader(board::SocketCan can, LiveMonitor& live);
  CanReader(const CanReader&) = delete;
  CanReader& operator=(const CanReader&) = delete;

 private:
  void run(std::stop_token stop);

  board::SocketCan can_;
  LiveMonitor& live_;
  std::jthread thread_;  // last: it starts once the members it uses exist, and stops before they go
};

}  // namespace lever::view
