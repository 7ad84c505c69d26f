#pragma once
// A candump -L log ("(1700000000.123456) vcan0 101#0011223344556677"), as the bridge's --record and candump -L
// write it: the frames with their times and interfaces, and how many lines were not frames.
#include <cstddef>
#include <istream>
#include <string>
#include <vector>

#include "lever/protocol/can_frame.hpp"

namespace lever::plot {

struct LoggedFrame {
  double t = 0.0;  // the log's time stamp, seconds
  std::string iface;
  protocol::CanFrame frame;
};

struct CandumpLog {
  std::vector<LoggedFrame> frames;
  std::size_t lines = 0;               // non-blank lines read
  std::size_t bad_lines = 0;           // of those, lines that are no classic CAN frame in candump -L form
  std::vector<std::string> first_bad;  // "LINE: text" of the first few, for the message
};

// One line, or nothing if it is no candump -L frame of a classic CAN frame (11-bit id, at most 8 bytes).
bool parse_candump_line(const std::string& line, LoggedFrame& out);

// Every line of the stream; lines longer than 4096 bytes are bad lines, never held whole.
CandumpLog read_candump(std::istream& in);

}  // namespace lever::plot
