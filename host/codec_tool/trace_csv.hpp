#pragma once
// Trace files for lever-codec: `t,x` (1-DoF) or `t,x,y,z` (3-DoF) in, `t,sent,x_hat[,y_hat,z_hat]` out.
#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace lever::tool {

// A problem in an input file, located to the line (0 when it concerns the file as a whole).
class TraceError : public std::runtime_error {
 public:
  TraceError(const std::filesystem::path& file, std::size_t line, const std::string& problem);
  const std::filesystem::path& file() const noexcept { return file_; }
  std::size_t line() const noexcept { return line_; }

 private:
  std::filesystem::path file_;
  std::size_t line_;
};

struct Trace {
  std::size_t dof = 1;         // 1 or 3
  std::vector<double> t;       // seconds, strictly increasing
  std::vector<double> values;  // samples() * dof, row-major

  std::size_t samples() const noexcept { return t.size(); }
  const double* row(std::size_t i) const noexcept { return values.data() + i * dof; }
};

// Reads and validates a whole trace ("-": stdin); throws TraceError naming file, line and problem. A UTF-8
// byte order mark before the header is skipped.
Trace read_trace(const std::filesystem::path& file);
Trace read_trace(std::istream& in, const std::filesystem::path& name);

}  // namespace lever::tool
