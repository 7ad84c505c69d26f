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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Perception-based deadband codec (Hinterseer et al.) on a recorded haptic trace.\n"
      "Input CSV: header t,x (1-DoF) or t,x,y,z (3-DoF), t in seconds, strictly increasing ('-': stdin).\n"
      "Writes one row per sample (t,sent,x_hat[,y_hat,z_hat]) and prints a JSON summary on stdout (on stderr\n"
      "when --out is '-', stdout)."};
  program::describe(app, "lever-codec");

  lever::codec::Config<double> config;
  std::string input, output;
  lever::codec_cli::add_options(app, config, kTrace, lever::codec_cli::kOffline);
  app.add_option("--in", input, "input trace CSV ('-': stdin)")->check(program::path());
  app.add_option("--out", output, "output CSV, written atomically ('-': stdout)")->check(program::path());

  auto* generate = app.add_subcommand("generate", "write an example trace from simple physics");
  lever::tool::GeneratorOptions gen;
  std::string gen_out;
  const program::Choices<lever::tool::TraceKind> kinds{{"velocity", lever::tool::TraceKind::velocity},
                                                       {"force", lever::tool::TraceKind::force},
                                                       {"force3", lever::tool::TraceKind::force3}};
  generate
      ->add_option("--kind", gen.kind,
                   "velocity: lever tapping a wall, encoder-differenced velocity [rad/s]; "
                   "force: its contact force through a strain gauge [N]; force3: 3-DoF sphere contact [N]")
      ->transform(program::one_of(kinds))
      ->required();
  generate->add_option("--seed", gen.seed, "random seed")->check(program::seed())->default_str("1");
  generate->add_option("--duration", gen.duration_s, "seconds of trace at 1 kHz")
      ->check(program::number({0.001, 3600.0, false, false, "a duration in seconds"}))
      ->default_str("10");
  generate->add_option("--out", gen_out, "output trace CSV, written atomically ('-': stdout)")
      ->required()
      ->check(program::path());
  generate->footer(program::kExitCodesHelp);
  app.require_subcommand(0, 1);

  if (const auto stop = program::parse(app, argc, argv)) return *stop;

  try {
    if (generate->parsed()) {
      program::OutputFile out(gen_out, "--out");
      const auto trace = lever::tool::generate_trace(gen);
      lever::tool::write_trace_csv(trace, [&out](std::string_view chunk) { out.write(chunk); });
      out.commit();
      fmt::print(out.is_stdout() ? stderr : stdout, "{}\n",
                 nlohmann::json{{"out", gen_out}, {"samples", trace.samples()}, {"dof", trace.dof}, {"seed", gen.seed}}
                     .dump());
      return 0;
    }
    if (input.empty() || output.empty()) return fail(program::kBadInput, "--in and --out are required (see --help)");

    program::OutputFile out(output, "--out", {input});
    const auto trace = lever::tool::read_trace(input);
    check_cutoff(trace, config.filter_hz);
    const auto run = lever::tool::run_codec(trace, config, [&out](std::string_view chunk) { out.write(chunk); });
    out.commit();

    const nlohmann::json summary{
        {"samples", run.samples},
        {"sent", run.sent},
        {"rate", static_cast<double>(run.sent) / static_cast<double>(run.samples)},
        {"rmse", run.rmse},
        {"max_error", run.max_error},
        {"dof", trace.dof},
        {"mode", std::string(lever::codec::name(config.mode))},
        {"p", config.p},
        {"floor", config.floor},
        {"filter_hz", config.filter_hz},
        {"in", input},
        {"out", output},
    };
    fmt::print(out.is_stdout() ? stderr : stdout, "{}\n", summary.dump());
    return 0;
  } catch (const lever::tool::TraceError& e) {
    return fail(program::kBadInput, e.what());
  } catch (const program::BadInput& e) {
    return fail(program::kBadInput, e.what());
  } catch (const std::exception& e) {
    return fail(program::kRuntimeFailure, e.what());
  }
}
