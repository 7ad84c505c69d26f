#include "trace_csv.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string_view>

#include "lever/program/text.hpp"

namespace lever::tool {
namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split_cells(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

double parse_cell(std::string_view cell, const std::filesystem::path& file, std::size_t line_no,
                  std::string_view column) {
  if (cell.empty()) throw TraceError(file, line_no, fmt::format("empty value in column '{}'", column));
  const std::string text(cell);  // strtod needs a terminated string
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size())
    throw TraceError(file, line_no,
                     fmt::format("'{}' in column '{}' is not a number", program::printable(cell), column));
  if (!std::isfinite(value) || errno == ERANGE)
    throw TraceError(file, line_no,
                     fmt::format("'{}' in column '{}' is not a finite number", program::printable(cell), column));
  return value;
}

}  // namespace

TraceError::TraceError(const std::filesystem::path& file, std::size_t line, const std::string& problem)
    : std::runtime_error(line > 0 ? fmt::format("{}:{}: {}", file.string(), line, problem)
                                  : fmt::format("{}: {}", file.string(), problem)),
      file_(file),
      line_(line) {}

Trace read_trace(const std::filesystem::path& file) {
  if (file == "-") return read_trace(std::cin, "stdin");
  std::ifstream in(file);
  if (!in) throw TraceError(file, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  if (std::filesystem::is_directory(file)) throw TraceError(file, 0, "cannot read: it is a directory");
  return read_trace(in, file);
}

Trace read_trace(std::istream& in, const std::filesystem::path& file) {
  Trace trace;
  std::string line;
  std::size_t line_no = 0;
  std::vector<std::string_view> columns;
  std::string header;
  while (std::getline(in, line)) {
    ++line_no;
    // A UTF-8 byte order mark, as spreadsheet programs write: invisible, and no part of the header.
    if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (trim(line).empty()) continue;  // blank lines carry no sample
    if (header.empty()) {
      header = line;
      columns = split_cells(header);
      if (columns.size() == 2 && columns[0] == "t" && columns[1] == "x") {
        trace.dof = 1;
      } else if (columns.size() == 4 && columns[0] == "t" && columns[1] == "x" && columns[2] == "y" &&
                 columns[3] == "z") {
        trace.dof = 3;
      } else {
        throw TraceError(file, line_no,
                         fmt::format("bad header '{}': expected 't,x' or 't,x,y,z'", program::printable(trim(line))));
      }
      continue;
    }
    const auto cells = split_cells(line);
    if (cells.size() != columns.size())
      throw TraceError(file, line_no, fmt::format("expected {} columns, found {}", columns.size(), cells.size()));
    const double t = parse_cell(cells[0], file, line_no, "t");
    if (!trace.t.empty() && !(t > trace.t.back()))
      throw TraceError(
          file, line_no,
          fmt::format("time {} does not increase (previous {})", program::printable(cells[0]), trace.t.back()));
    trace.t.push_back(t);
    for (std::size_t c = 1; c < cells.size(); ++c)
      trace.values.push_back(parse_cell(cells[c], file, line_no, columns[c]));
  }
  if (in.bad()) throw TraceError(file, line_no, fmt::format("read error: {}", std::strerror(errno)));
  if (header.empty()) throw TraceError(file, 0, "empty file: expected header 't,x' or 't,x,y,z'");
  if (trace.t.empty()) throw TraceError(file, 0, "no samples after the header");
  return trace;
}

}  // namespace lever::tool
