// lever-codec's input validation: every bad file is named with its line and problem.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "lever/program/exit_codes.hpp"
#include "lever/program/output_file.hpp"
#include "trace_csv.hpp"

namespace fs = std::filesystem;
using lever::tool::read_trace;
using lever::tool::TraceError;

namespace {

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "lever-test-XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path write(const std::string& name, const std::string& content) const {
    std::ofstream(path_ / name) << content;
    return path_ / name;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The message read_trace gives for a file with this content.
std::string error_for(const std::string& content) {
  TempDir dir;
  const auto file = dir.write("trace.csv", content);
  try {
    read_trace(file);
  } catch (const TraceError& e) {
    return std::string(e.what()).substr(file.string().size());
  }
  return "no error";
}

}  // namespace

TEST_CASE("a 1-DoF and a 3-DoF trace are read", "[tool][csv]") {
  TempDir dir;
  const auto one = read_trace(dir.write("a.csv", "t,x\n0,1.5\n0.001,-2e-3\n"));
  CHECK(one.dof == 1);
  REQUIRE(one.samples() == 2);
  CHECK(one.row(1)[0] == -2e-3);
  const auto three = read_trace(dir.write("b.csv", "t,x,y,z\r\n0,1,2,3\r\n0.5, 4 ,5,6\r\n\r\n"));
  CHECK(three.dof == 3);
  REQUIRE(three.samples() == 2);
  CHECK(three.row(1)[0] == 4.0);
  CHECK(three.row(1)[2] == 6.0);
}

TEST_CASE("bad traces are rejected with file, line and problem", "[tool][csv]") {
  CHECK(error_for("") == ": empty file: expected header 't,x' or 't,x,y,z'");
  CHECK(error_for("t,x\n") == ": no samples after the header");
  CHECK(error_for("time,x\n0,1\n") == ":1: bad header 'time,x': expected 't,x' or 't,x,y,z'");
  CHECK(error_for("t,x,y\n0,1,2\n") == ":1: bad header 't,x,y': expected 't,x' or 't,x,y,z'");
  CHECK(error_for("t,x\n0,1\n0.001,abc\n") == ":3: 'abc' in column 'x' is not a number");
  CHECK(error_for("t,x\n0,1\n0.001,1.5x\n") == ":3: '1.5x' in column 'x' is not a number");
  CHECK(error_for("t,x\n0,nan\n") == ":2: 'nan' in column 'x' is not a finite number");
  CHECK(error_for("t,x\n0,-inf\n") == ":2: '-inf' in column 'x' is not a finite number");
  CHECK(error_for("t,x\n0,1e999\n") == ":2: '1e999' in column 'x' is not a finite number");
  CHECK(error_for("t,x\n0,1\n0,2\n") == ":3: time 0 does not increase (previous 0)");
  CHECK(error_for("t,x\n0.002,1\n0.001,2\n") == ":3: time 0.001 does not increase (previous 0.002)");
  CHECK(error_for("t,x\n0,1,2\n") == ":2: expected 2 columns, found 3");
  CHECK(error_for("t,x,y,z\n0,1,2\n") == ":2: expected 4 columns, found 3");
  CHECK(error_for("t,x\n0,\n") == ":2: empty value in column 'x'");
}

TEST_CASE("a missing file is named", "[tool][csv]") {
  CHECK_THROWS_WITH(read_trace("/nonexistent/trace.csv"),
                    "/nonexistent/trace.csv: cannot open: No such file or directory");
}

TEST_CASE("an atomic write leaves either the whole file or nothing", "[tool][csv]") {
  TempDir dir;
  const auto file = dir.path() / "out.csv";
  lever::program::OutputFile::write_all(file.string(), "t,sent,x_hat\n0,1,1\n");
  std::ifstream in(file);
  std::string content((std::istreambuf_iterator<char>(in)), {});
  CHECK(content == "t,sent,x_hat\n0,1,1\n");
  CHECK_THROWS_AS(lever::program::OutputFile::write_all((dir.path() / "missing" / "out.csv").string(), "x"),
                  lever::program::BadInput);
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path())) ++entries;
  CHECK(entries == 1);  // no temporary left behind
}
