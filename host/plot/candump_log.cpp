#include "candump_log.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>

#include "lever/program/text.hpp"

namespace lever::plot {
namespace {

constexpr std::size_t kMaxLine = 4096;  // a candump -L line is under 100 bytes
constexpr std::size_t kBadShown = 5;

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

bool parse_candump_line(const std::string& line, LoggedFrame& out) {
  // "(SECONDS.MICROS) IFACE ID#HEX"
  if (line.size() < 8 || line.front() != '(') return false;
  const auto close = line.find(") ");
  if (close == std::string::npos) return false;
  const std::string stamp = line.substr(1, close - 1);
  if (stamp.find('.') == std::string::npos) return false;
  for (const char c : stamp)
    if (!std::isdigit(static_cast<unsigned char>(c)) && c != '.') return false;
  const char* end = stamp.data() + stamp.size();
  if (std::from_chars(stamp.data(), end, out.t).ptr != end || !std::isfinite(out.t)) return false;
  const auto space = line.find(' ', close + 2);
  if (space == std::string::npos || space == close + 2) return false;
  out.iface = line.substr(close + 2, space - close - 2);
  std::string rest = line.substr(space + 1);
  while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.back()))) rest.pop_back();
  const auto hash = rest.find('#');
  // Classic frames only: a 3-digit standard id; an extended id (8 digits) or a CAN FD frame ("##") is not the
  // lever protocol's, and counted as a bad line.
  if (hash != 3) return false;
  std::uint32_t id = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const int d = hex_digit(rest[i]);
    if (d < 0) return false;
    id = id * 16 + static_cast<std::uint32_t>(d);
  }
  const std::string hex = rest.substr(4);
  if (hex.size() % 2 != 0 || hex.size() > 16 || id > protocol::kMaxStandardId) return false;
  out.frame = {};
  out.frame.id = id;
  out.frame.dlc = static_cast<std::uint8_t>(hex.size() / 2);
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    const int hi = hex_digit(hex[i]), lo = hex_digit(hex[i + 1]);
    if (hi < 0 || lo < 0) return false;
    out.frame.data[i / 2] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return true;
}

CandumpLog read_candump(std::istream& in) {
  CandumpLog log;
  std::string line;
  std::size_t number = 0;
  auto bad = [&](const std::string& text) {
    ++log.bad_lines;
    if (log.first_bad.size() < kBadShown)
      log.first_bad.push_back(fmt::format("line {}: {}", number, program::printable(text, 60)));
  };
  while (true) {
    line.clear();
    bool too_long = false;
    int c = 0;
    while ((c = in.get()) != EOF && c != '\n') {
      if (line.size() < kMaxLine) {
        line.push_back(static_cast<char>(c));
      } else {
        too_long = true;
      }
    }
    if (c == EOF && line.empty()) break;
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    ++log.lines;
    LoggedFrame f;
    if (too_long) {
      bad(fmt::format("longer than {} bytes", kMaxLine));
    } else if (parse_candump_line(line, f)) {
      log.frames.push_back(std::move(f));
    } else {
      bad(line);
    }
    if (c == EOF) break;
  }
  return log;
}

}  // namespace lever::plot
