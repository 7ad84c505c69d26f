#include "sweep_runner.hpp"

#include <fmt/format.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <thread>
#include <vector>

#include "lever/program/exit_codes.hpp"
#include "lever/program/gnuplot.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/text.hpp"

namespace lever::hil {

void prepare_sweep_dir(const std::string& out_dir, std::initializer_list<const char*> files) {
  namespace fs = std::filesystem;
  const fs::path dir(out_dir);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw program::BadInput(fmt::format("--out {} exists and is not a directory", program::printable(out_dir)));
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", program::printable(out_dir), ec.message()));
  // Refused now, not after the runs: a file that is a device, a link or a directory.
  for (const char* name : files) program::OutputFile((dir / name).string(), "--out");
}

void run_in_parallel(std::size_t count, int threads, std::size_t every, const std::function<void(std::size_t)>& run,
                     const std::function<std::string(std::size_t)>& label) {
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex print;
  const bool tty = isatty(fileno(stderr));
  auto worker = [&] {
    for (std::size_t i = next++; i < count; i = next++) {
      run(i);
      const std::size_t finished = ++done;
      std::lock_guard lock(print);
      if (tty || finished == count || finished % every == 0)
        fmt::print(stderr, "{}sweep: {}/{} runs ({}){}", tty ? "\r" : "", finished, count, label(i),
                   tty ? "   " : "\n");
    }
  };
  std::vector<std::thread> pool;
  for (int j = 0; j < threads; ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (tty) fmt::print(stderr, "\n");
}

void write_sweep(const std::filesystem::path& dir, const SweepTable& table, const std::string& plot_script) {
  program::OutputFile::write_all((dir / "sweep.csv").string(), table.runs_csv(), "--out");
  program::OutputFile::write_all((dir / "summary.csv").string(), table.summary_csv(), "--out");
  program::OutputFile::write_all((dir / "plots.gp").string(), plot_script, "--out");
}

int plot_sweep(const std::filesystem::path& dir) {
  const int status = program::run_gnuplot(dir / "plots.gp");
  if (status == 0) return 0;
  fmt::print(stderr, "lever-hil: gnuplot {}; the CSV files are in {} (install gnuplot-nox for plots)\n",
             status == 127 ? "could not be started" : fmt::format("failed (exit status {})", status),
             program::printable(dir.string()));
  return program::kRuntimeFailure;
}

}  // namespace lever::hil
