// lever-codec: runs the perceptual deadband codec on a recorded trace, or generates example traces.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "codec_run.hpp"
#include "lever/codec_cli/codec_options.hpp"
#include "lever/program/choices.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/parse.hpp"
#include "trace_csv.hpp"
#include "trace_generator.hpp"

namespace {

namespace program = lever::program;

// One signal in whatever unit the trace is in.
constexpr lever::codec_cli::Signal kTrace{"", "", "signal units"};

int fail(int code, const std::string& message) {
  fmt::print(stderr, "lever-codec: {}\n", message);
  return code;
}

// The prefilter's cut-off must stay below the trace's Nyquist frequency, from its median sample interval.
void check_cutoff(const lever::tool::Trace& trace, double filter_hz) {
  if (filter_hz <= 0.0 || trace.samples() < 2) return;
  std::vector<double> dt(trace.samples() - 1);
  for (std::size_t i = 1; i < trace.samples(); ++i) dt[i - 1] = trace.t[i] - trace.t[i - 1];
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const double rate = 1.0 / dt[dt.size() / 2];
  if (filter_hz >= rate / 2)
    throw program::BadInput(
        fmt::format("--filter-hz must be below the trace's Nyquist frequency ({} Hz at {} Hz), got {}",
                    program::short_number(rate / 2), program::short_number(rate), program::short_number(filter_hz)));
}

// lever-codec --in --out: the codec over a recorded trace.
struct RunOptions {
  lever::codec::Config<double> config;
  std::string input, output;
};

void add_run_options(CLI::App& app, RunOptions& o) {
  lever::codec_cli::add_options(app, o.config, kTrace, lever::codec_cli::kOffline);
  app.add_option("--in", o.input, "input trace CSV ('-': stdin)")->check(program::path());
  app.add_option("--out", o.output, "output CSV, written atomically ('-': stdout)")->check(program::path());
}

// lever-codec generate: an example trace.
struct GenerateCommand {
  CLI::App* app = nullptr;
  lever::tool::GeneratorOptions options;
  std::string out;
};

void add_generate_command(CLI::App& app, GenerateCommand& g) {
  g.app = app.add_subcommand("generate", "write an example trace from simple physics");
  static const auto kinds = program::choices_of(lever::tool::kAllTraceKinds);
  g.app
      ->add_option("--kind", g.options.kind,
                   "velocity: lever tapping a wall, encoder-differenced velocity [rad/s]; "
                   "force: its contact force through a strain gauge [N]; force3: 3-DoF sphere contact [N]")
      ->transform(program::one_of(kinds))
      ->required();
  g.app->add_option("--seed", g.options.seed, "random seed")->check(program::seed())->default_str("1");
  g.app->add_option("--duration", g.options.duration_s, "seconds of trace at 1 kHz")
      ->check(program::number({0.001, 3600.0, false, false, "a duration in seconds"}))
      ->default_str("10");
  g.app->add_option("--out", g.out, "output trace CSV, written atomically ('-': stdout)")
      ->required()
      ->check(program::path());
  g.app->footer(program::kExitCodesHelp);
}

int generate(const GenerateCommand& g) {
  program::OutputFile out(g.out, "--out");
  const auto trace = lever::tool::generate_trace(g.options);
  lever::tool::write_trace_csv(trace, [&out](std::string_view chunk) { out.write(chunk); });
  out.commit();
  fmt::print(out.is_stdout() ? stderr : stdout, "{}\n",
             nlohmann::json{{"out", g.out}, {"samples", trace.samples()}, {"dof", trace.dof}, {"seed", g.options.seed}}
                 .dump());
  return 0;
}

int run(const RunOptions& o) {
  if (o.input.empty() || o.output.empty()) return fail(program::kBadInput, "--in and --out are required (see --help)");
  program::OutputFile out(o.output, "--out", {o.input});
  const auto trace = lever::tool::read_trace(o.input);
  check_cutoff(trace, o.config.filter_hz);
  const auto result = lever::tool::run_codec(trace, o.config, [&out](std::string_view chunk) { out.write(chunk); });
  out.commit();
  const nlohmann::json summary{
      {"samples", result.samples},
      {"sent", result.sent},
      {"rate", static_cast<double>(result.sent) / static_cast<double>(result.samples)},
      {"rmse", result.rmse},
      {"max_error", result.max_error},
      {"dof", trace.dof},
      {"mode", std::string(lever::codec::name(o.config.mode))},
      {"p", o.config.p},
      {"floor", o.config.floor},
      {"filter_hz", o.config.filter_hz},
      {"in", o.input},
      {"out", o.output},
  };
  fmt::print(out.is_stdout() ? stderr : stdout, "{}\n", summary.dump());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Perception-based deadband codec (Hinterseer et al.) on a recorded haptic trace.\n"
      "Input CSV: header t,x (1-DoF) or t,x,y,z (3-DoF), t in seconds, strictly increasing ('-': stdin).\n"
      "Writes one row per sample (t,sent,x_hat[,y_hat,z_hat]) and prints a JSON summary on stdout (on stderr\n"
      "when --out is '-', stdout)."};
  program::describe(app, "lever-codec");
  RunOptions run_options;
  add_run_options(app, run_options);
  GenerateCommand generate_command;
  add_generate_command(app, generate_command);
  app.require_subcommand(0, 1);
  if (const auto stop = program::parse(app, argc, argv)) return *stop;

  try {
    return generate_command.app->parsed() ? generate(generate_command) : run(run_options);
  } catch (const lever::tool::TraceError& e) {
    return fail(program::kBadInput, e.what());
  } catch (const program::BadInput& e) {
    return fail(program::kBadInput, e.what());
  } catch (const std::exception& e) {
    return fail(program::kRuntimeFailure, e.what());
  }
}
