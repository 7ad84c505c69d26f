// The codec's options as every program declares them (codec_cli/): names, ranges, defaults, overrides.
#include <catch2/catch.hpp>
#include <string>

#include "lever/codec_cli/codec_options.hpp"

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
