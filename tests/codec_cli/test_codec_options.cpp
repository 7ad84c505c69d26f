// The codec's options as every program declares them (codec_cli/): names, ranges, defaults, overrides; and its
// keys as a configuration file declares them, with the options' ranges.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <string>
#include <utility>
#include <vector>

#include "lever/codec_cli/codec_options.hpp"
#include "lever/program/config_schema.hpp"

namespace codec_cli = lever::codec_cli;
using codec_cli::Param;
using lever::codec::Config;
using lever::codec::Mode;

namespace {

// CLI11's message for the first refused option, or "" when the line parses.
std::string refusal(CLI::App& app, const std::string& line) {
  try {
    app.parse(line);
    return {};
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
}

}  // namespace

TEST_CASE("every parameter is an option, named with the signal's suffix") {
  CLI::App app;
  Config<double> config;
  codec_cli::add_options(app, config, codec_cli::kVelocity, codec_cli::kOnWire);
  for (const Param param : codec_cli::kAllParams)
    CHECK(app.get_option_no_throw(codec_cli::option_name(param, codec_cli::kVelocity)) != nullptr);
  CHECK(codec_cli::option_name(Param::filter_hz, codec_cli::kForce) == "--filter-hz-force");
  CHECK(refusal(app, "--mode-velocity predictive --p-velocity 0.2 --floor-velocity 0.5 --filter-hz-velocity 30") == "");
  CHECK(config.mode == Mode::predictive);
  CHECK(config.p == 0.2);
  CHECK(config.floor == 0.5);
  CHECK(config.filter_hz == 30.0);
}

TEST_CASE("the floor on the wire is what a CAN command frame carries, and a program may refuse 0") {
  CHECK(codec_cli::kOnWire.floor_max == 65.535);
  CLI::App app;
  Config<double> config;
  codec_cli::add_options(app, config, codec_cli::kForce, codec_cli::kOnWire, {Param::floor});
  CHECK(refusal(app, "--floor-force 65.535") == "");
  CHECK(refusal(app, "--floor-force 65.536") == "--floor-force: must be a floor in N in [0, 65.535], got 65.536");
  CHECK(refusal(app, "--floor-force 0") == "");

  codec_cli::Limits no_zero = codec_cli::kOnWire;
  no_zero.floor_zero = false;
  CLI::App variant;
  codec_cli::add_options(variant, config, codec_cli::kForce, no_zero, {Param::floor});
  CHECK(refusal(variant, "--floor-force 0") == "--floor-force: must be a floor in N in (0, 65.535], got 0");
}

TEST_CASE("a default the range refuses is not shown: leaving the option out is the only way to have it") {
  CLI::App app;
  Config<double> config;
  codec_cli::add_options(app, config, {"", "", "signal units"}, codec_cli::kOffline);
  CHECK(app.get_option("--p")->get_default_str() == "0.1");
  CHECK(app.get_option("--mode")->get_default_str() == "deadband");
  CHECK(app.get_option("--filter-hz")->get_default_str().empty());
  CHECK(app.get_option("--filter-hz")->get_description().find("(default: off)") != std::string::npos);
  CHECK(refusal(app, "--filter-hz 0") == "--filter-hz: must be a cut-off in Hz > 0, got 0");
  CHECK(refusal(app, "--filter-hz 800") == "");  // the trace's own Nyquist is checked once it is read
}

TEST_CASE("per-direction overrides replace the option for both, and only where given") {
  CLI::App app;
  Config<double> both;
  codec_cli::Overrides velocity, force;
  codec_cli::add_options(app, both, codec_cli::kBothDirections, codec_cli::kOnWire,
                         codec_cli::kAll.without(Param::floor));
  codec_cli::add_overrides(app, velocity, both, codec_cli::kVelocity, codec_cli::kOnWire);
  codec_cli::add_overrides(app, force, both, codec_cli::kForce, codec_cli::kOnWire);
  CHECK(app.get_option_no_throw("--floor") == nullptr);
  CHECK(app.get_option("--p-velocity")->get_description().find("overrides --p") != std::string::npos);
  CHECK(app.get_option("--p-velocity")->get_default_str().empty());
  // No --floor to override: the floor's default is the one for both.
  CHECK(app.get_option("--floor-force")->get_description().find("overrides") == std::string::npos);
  CHECK(app.get_option("--floor-force")->get_default_str() == "0");

  REQUIRE(refusal(app, "--p 0.2 --p-force 0.3 --mode-velocity predictive --floor-force 0.05") == "");
  const Config<double> v = codec_cli::resolve(both, velocity), f = codec_cli::resolve(both, force);
  CHECK(v.mode == Mode::predictive);
  CHECK(f.mode == Mode::deadband);
  CHECK(v.p == 0.2);
  CHECK(f.p == 0.3);
  CHECK(v.floor == 0.0);
  CHECK(f.floor == 0.05);
  CHECK(refusal(app, "--p-velocity 1") == "--p-velocity: must be a fraction in [0, 1), got 1");
}

TEST_CASE("a program that sends the values says the steps the frame rounds them to") {
  CLI::App app;
  Config<double> config;
  codec_cli::add_options(app, config, {"", "", "rad/s or N"}, codec_cli::kSentOverCan);
  CHECK(app.get_option("--p")->get_description().find("steps of 0.0001") != std::string::npos);
  CHECK(app.get_option("--floor")->get_description().find("steps of 0.001") != std::string::npos);
  CHECK(app.get_option("--filter-hz")->get_description().find("steps of 0.1") != std::string::npos);
  CHECK(app.get_option("--mode")->get_description().find("steps") == std::string::npos);
}

namespace {

// The schema's words for the first refused key, or "" when the text loads.
std::string key_refusal(lever::program::ConfigSchema& schema, const std::string& toml) {
  return schema.load_string(toml, "f.toml").value_or("");
}

// "must be a fraction in [0, 1)": a refusal's words up to the value, which an option quotes as typed and a key
// prints as the number it read.
std::string range_words(const std::string& refusal) {
  const auto must = refusal.find("must be");
  return must == std::string::npos ? refusal : refusal.substr(must, refusal.rfind(", got") - must);
}

}  // namespace

TEST_CASE("a configuration file's keys are the options' names in TOML's spelling, with their help") {
  lever::program::ConfigSchema schema;
  Config<double> config;
  codec_cli::bind_keys(schema, "codec.force", config, codec_cli::kForce, codec_cli::kOnWire);
  CHECK(schema.keys("codec.force.") ==
        std::vector<std::string>{"codec.force.mode", "codec.force.p", "codec.force.floor", "codec.force.filter_hz"});
  CHECK(codec_cli::option_name(Param::filter_hz, codec_cli::kForce) == "--filter-hz-force");
  // The unit has a place of its own in a printed key; an option says it in its help.
  const std::string printed = schema.print();
  CHECK(printed.find("floor = 0.0  # N: absolute deadband floor (0: the paper's rule)\n") != std::string::npos);
  CHECK(printed.find("filter_hz = 0.0  # Hz: low-pass prefilter cut-off (0: off)\n") != std::string::npos);
  CHECK(printed.find("p = 0.1  # Weber fraction p, the relative deadband (0.1: 10 %)\n") != std::string::npos);
  CLI::App app;
  codec_cli::add_options(app, config, codec_cli::kForce, codec_cli::kOnWire);
  CHECK(app.get_option("--floor-force")->get_description() ==
        "TOP->HSI force: absolute deadband floor in N (0: the paper's rule)");
  REQUIRE(key_refusal(schema, "[codec.force]\nmode = \"predictive\"\np = 0.2\nfloor = 0.5\nfilter_hz = 30") == "");
  CHECK(config.mode == Mode::predictive);
  CHECK(config.p == 0.2);
  CHECK(config.floor == 0.5);
  CHECK(config.filter_hz == 30.0);
}

TEST_CASE("a key refuses what its option refuses, a number in the same words, at every bound") {
  codec_cli::Limits no_zero_floor = codec_cli::kOnWire;
  no_zero_floor.floor_zero = false;
  const std::pair<const char*, codec_cli::Limits> every_limits[] = {{"kOnWire", codec_cli::kOnWire},
                                                                    {"kSentOverCan", codec_cli::kSentOverCan},
                                                                    {"kOffline", codec_cli::kOffline},
                                                                    {"a floor above 0", no_zero_floor}};
  // Each bound of every range, a step inside and outside it, and what no range takes.
  const std::vector<std::string> numbers = {"-1",    "-0.0001", "0",      "0.0001", "0.5",    "0.9999",
                                            "1",     "1.5",     "6.5535", "7",      "65.535", "65.536",
                                            "499.9", "500",     "500.1",  "1e300",  "nan",    "inf"};
  const std::vector<std::string> modes = {"deadband", "predictive", "bogus"};
  for (const auto& [limits_name, limits] : every_limits) {
    for (const Param param : codec_cli::kAllParams) {
      const bool is_mode = param == Param::mode;
      for (const std::string& value : is_mode ? modes : numbers) {
        CAPTURE(limits_name, codec_cli::key_name(param), value);
        CLI::App app;
        Config<double> from_options, from_file;
        codec_cli::add_options(app, from_options, codec_cli::kVelocity, limits);
        lever::program::ConfigSchema schema;
        codec_cli::bind_keys(schema, "codec.motion", from_file, codec_cli::kVelocity, limits);
        const std::string by_option = refusal(app, codec_cli::option_name(param, codec_cli::kVelocity) + " " + value);
        const std::string by_key = key_refusal(
            schema,
            fmt::format("[codec.motion]\n{} = {}", codec_cli::key_name(param), is_mode ? '"' + value + '"' : value));
        CHECK(by_option.empty() == by_key.empty());
        // A choice's list reads as each syntax lists all its choices ("deadband or predictive" on a command line).
        if (!is_mode) CHECK(range_words(by_option) == range_words(by_key));
      }
    }
  }
}
