// lever-codec: runs the perceptual deadband codec on a recorded trace, or generates example traces.
#include <fmt/format.h>

#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "codec_run.hpp"
#include "lever/program/parse.hpp"
#include "trace_csv.hpp"
#include "trace_generator.hpp"

namespace {

constexpr int kBadInput = lever::program::kBadInput;

int fail(const std::string& message) {
  fmt::print(stderr, "lever-codec: {}\n", message);
  return kBadInput;
}

}  // namespace

int main(int argc, char** argv) {
  using lever::codec::Mode;
  CLI::App app{
      "Perception-based deadband codec (Hinterseer et al.) on a recorded haptic trace.\n"
      "Input CSV: header t,x (1-DoF) or t,x,y,z (3-DoF), t in seconds, strictly increasing.\n"
      "Writes one row per sample (t,sent,x_hat[,y_hat,z_hat]) and prints a JSON summary on stdout.\n"
      "Exit codes: 0 success, 2 bad input or arguments."};
  app.name("lever-codec");

  lever::codec::Config<double> config;
  std::string input, output;
  const std::map<std::string, Mode> modes{{"deadband", Mode::deadband}, {"predictive", Mode::predictive}};
  app.add_option("--mode", config.mode, "deadband (zero-order hold) or predictive (linear predictor)")
      ->transform(CLI::CheckedTransformer(modes, CLI::ignore_case))
      ->default_str("deadband");
  app.add_option("--p", config.p, "Weber fraction p: relative deadband, e.g. 0.1 for 10 %")
      ->check(CLI::NonNegativeNumber)
      ->default_str("0.1");
  app.add_option("--floor", config.floor, "absolute deadband floor in signal units (0 = the paper's rule)")
      ->check(CLI::NonNegativeNumber)
      ->default_str("0");
  app.add_option("--filter-hz", config.filter_hz, "low-pass prefilter cut-off in Hz (default: off)")
      ->check(CLI::PositiveNumber);
  app.add_option("--in", input, "input trace CSV");
  app.add_option("--out", output, "output CSV (written atomically)");

  auto* generate = app.add_subcommand("generate", "write an example trace from simple physics");
  lever::tool::GeneratorOptions gen;
  std::string gen_out;
  const std::map<std::string, lever::tool::TraceKind> kinds{{"velocity", lever::tool::TraceKind::velocity},
                                                            {"force", lever::tool::TraceKind::force},
                                                            {"force3", lever::tool::TraceKind::force3}};
  generate
      ->add_option("--kind", gen.kind,
                   "velocity: lever tapping a wall, encoder-differenced velocity [rad/s]; "
                   "force: its contact force through a strain gauge [N]; force3: 3-DoF sphere contact [N]")
      ->transform(CLI::CheckedTransformer(kinds, CLI::ignore_case))
      ->required();
  generate->add_option("--seed", gen.seed, "random seed")->default_str("1");
  generate->add_option("--duration", gen.duration_s, "seconds of trace at 1 kHz")
      ->check(CLI::Range(0.001, 3600.0))
      ->default_str("10");
  generate->add_option("--out", gen_out, "output trace CSV")->required();
  app.require_subcommand(0, 1);

  if (const auto stop = lever::program::parse(app, argc, argv)) return *stop;

  try {
    if (generate->parsed()) {
      const auto trace = lever::tool::generate_trace(gen);
      lever::tool::write_file_atomically(gen_out, lever::tool::format_trace_csv(trace));
      fmt::print("{}\n",
                 nlohmann::json{{"out", gen_out}, {"samples", trace.samples()}, {"dof", trace.dof}, {"seed", gen.seed}}
                     .dump());
      return 0;
    }
    if (input.empty() || output.empty()) return fail("--in and --out are required (see --help)");

    const auto trace = lever::tool::read_trace(input);
    const auto run = lever::tool::run_codec(trace, config);
    lever::tool::write_file_atomically(output, run.csv);

    const nlohmann::json summary{
        {"samples", run.samples},
        {"sent", run.sent},
        {"rate", static_cast<double>(run.sent) / static_cast<double>(run.samples)},
        {"rmse", run.rmse},
        {"max_error", run.max_error},
        {"dof", trace.dof},
        {"mode", config.mode == Mode::predictive ? "predictive" : "deadband"},
        {"p", config.p},
        {"floor", config.floor},
        {"filter_hz", config.filter_hz},
        {"in", input},
        {"out", output},
    };
    fmt::print("{}\n", summary.dump());
    return 0;
  } catch (const lever::tool::TraceError& e) {
    return fail(e.what());
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}
