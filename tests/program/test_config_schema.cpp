// ConfigSchema's fields beyond lever-fw's: optional integers and numbers, numbers in a half-open range, durations,
// refused empty strings, text with a syntax of its own, text kept as another type, custom fields. lever-fw's own keys
// are held by tests/cli/lever_fw_cli.sh.
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "lever/program/config_schema.hpp"
#include "lever/program/numbers.hpp"

using lever::program::ConfigSchema;

namespace {

struct Settings {
  std::optional<std::uint8_t> id;
  std::string name = "a";
  std::string list = "x";
  std::filesystem::path file;
  std::uint64_t bytes = 0;
  std::chrono::microseconds poll{5'000};
  std::chrono::seconds timeout{2};
  std::optional<double> bound;
  std::optional<unsigned> pin = 4;  // "": none
  double cutoff_hz = 0.0;
};

// A pin by number, or none for "".
std::optional<unsigned> pin_from_text(const std::string& text) {
  if (text.empty()) return std::nullopt;
  if (text.find_first_not_of("0123456789") != std::string::npos) throw std::invalid_argument("not a pin number");
  return static_cast<unsigned>(std::stoul(text));
}

ConfigSchema schema_for(Settings& s) {
  ConfigSchema c;
  c.integer("id", s.id, 0, 255, "", "an id, random while unset");
  c.text("name", s.name, "a name", ConfigSchema::Empty::refused);
  c.parsed_text(
      "list", "only x or y",
      [&s](const std::string& text, const std::filesystem::path&) {
        if (text != "x" && text != "y") throw std::invalid_argument("'" + text + "' is neither x nor y");
        s.list = text;
      },
      [&s] { return ConfigSchema::quoted(s.list); });
  c.parsed_text(
      "file", "relative to the configuration",
      [&s](const std::string& text, const std::filesystem::path& from) { s.file = from.parent_path() / text; },
      [&s]() -> std::optional<std::string> {
        if (s.file.empty()) return std::nullopt;  // none yet: "" would not load
        return ConfigSchema::quoted(s.file.string());
      });
  c.custom(
      "size_kb", "kB", "kept in bytes",
      [&s](const toml::node& n) -> std::optional<std::string> {
        double kb = 0;
        if (auto e = ConfigSchema::read_number(n, 0, 10, "kB", kb)) return e;
        s.bytes = static_cast<std::uint64_t>(kb * 1000);
        return std::nullopt;
      },
      [&s] { return ConfigSchema::number_text(static_cast<double>(s.bytes) / 1000); });
  c.duration("poll_us", s.poll, 100, 1'000'000, "us", "poll period");
  c.duration("timeout_s", s.timeout, 1, 60, "s", "give up after");
  c.number("bound", s.bound, -10.0, 10.0, "N", "a bound, none while unset");
  c.text_as<std::optional<unsigned>>(
      "pin", s.pin, pin_from_text, [](const std::optional<unsigned>& p) { return p ? std::to_string(*p) : ""; },
      "a pin; empty: none");
  // Gone once the schema is built, as a caller's text for the range's name may be.
  std::string what = "a cut-off in Hz";
  c.number("cutoff_hz", s.cutoff_hz, lever::program::Bounds{0.0, 500.0, false, true, what}, "Hz", "a cut-off");
  what = "overwritten";
  return c;
}

}  // namespace

TEST_CASE("an optional integer: unset until loaded, printed as a comment while unset", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  CHECK(schema.value("id") == "");
  CHECK(schema.value_text("id") == "");
  CHECK(schema.print().find("# id (unset)  # an id, random while unset\n") != std::string::npos);
  REQUIRE_FALSE(schema.load_string("id = 7", "f.toml"));
  REQUIRE(s.id);
  CHECK(*s.id == 7);
  CHECK(schema.value("id") == "7");
  CHECK(schema.print().find("id = 7  # an id") != std::string::npos);
  CHECK(schema.load_string("id = 256", "f.toml") == "f.toml: id: must be a whole number in [0, 255], got 256");
}

TEST_CASE("a text that must not be empty", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  CHECK(schema.load_string("name = \"\"", "f.toml") == "f.toml: name: must not be empty");
  CHECK(schema.load_string("name = 5", "f.toml") == "f.toml: name: must be a string, got an integer");
  CHECK(s.name == "a");
  s.name.clear();  // a default of none: unset, not a "" that would not load back
  CHECK(schema.print().find("# name (unset)  # a name\n") != std::string::npos);
  CHECK(schema.value("name") == "");
}

TEST_CASE("a parsed text: its own syntax, and paths from the file that holds them", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  REQUIRE_FALSE(schema.load_string("list = \"y\"\nfile = \"k.key\"", "/etc/lever/f.toml"));
  CHECK(s.list == "y");
  CHECK(s.file == "/etc/lever/k.key");
  CHECK(schema.value_text("list") == "y");
  CHECK(schema.load_string("list = \"z\"", "f.toml") == "f.toml: list: 'z' is neither x nor y");
  CHECK(schema.load_string("list = \"\"", "f.toml") == "f.toml: list: must not be empty");
  CHECK(s.list == "y");
  // From elsewhere than a file (--set): no directory to take it from.
  REQUIRE_FALSE(schema.load_assignment("file=\"k.key\"", "--set"));
  CHECK(s.file == "k.key");
}

TEST_CASE("a custom field: the number checks' words, its own units, and a print that reads back", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  REQUIRE_FALSE(schema.load_string("size_kb = 2.5\nid = 3\nname = \"n\"", "f.toml"));
  CHECK(s.bytes == 2500);
  CHECK(schema.load_string("size_kb = nan", "f.toml") == "f.toml: size_kb: must be a number of kB in [0, 10], got nan");
  CHECK(schema.load_string("size_kb = \"1\"", "f.toml") == "f.toml: size_kb: must be a number, got a string");
  Settings again;
  auto reread = schema_for(again);
  CHECK(reread.load_string(schema.print(), "printed.toml") == std::nullopt);
  CHECK(reread.print() == schema.print());
  CHECK(schema.print().find("# file (unset)") != std::string::npos);
}

TEST_CASE("a duration: a whole number of its own unit", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  CHECK(schema.value("poll_us") == "5000");
  CHECK(schema.value("timeout_s") == "2");
  REQUIRE_FALSE(schema.load_string("poll_us = 250\ntimeout_s = 7", "f.toml"));
  CHECK(s.poll == std::chrono::microseconds(250));
  CHECK(s.timeout == std::chrono::seconds(7));
  CHECK(schema.value("poll_us") == "250");
  CHECK(schema.print().find("poll_us = 250  # us: poll period\n") != std::string::npos);
  CHECK(schema.print().find("timeout_s = 7  # s: give up after\n") != std::string::npos);
  // The integers' checks and words, a float with no fraction taken as the integers take it.
  CHECK(schema.load_string("poll_us = 99", "f.toml") ==
        "f.toml: poll_us: must be a whole number in [100, 1000000], got 99");
  CHECK(schema.load_string("poll_us = 250.5", "f.toml") ==
        "f.toml: poll_us: must be a whole number in [100, 1000000], got 250.5");
  CHECK(schema.load_string("timeout_s = \"1\"", "f.toml") ==
        "f.toml: timeout_s: must be a whole number in [1, 60], got a string");
  REQUIRE_FALSE(schema.load_string("poll_us = 1000.0", "f.toml"));
  CHECK(s.poll == std::chrono::milliseconds(1));
  CHECK(s.timeout == std::chrono::seconds(7));
}

TEST_CASE("an optional number: unset until loaded, printed as a comment while unset", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  CHECK(schema.value("bound") == "");
  CHECK(schema.print().find("# bound (unset)  # N: a bound, none while unset\n") != std::string::npos);
  REQUIRE_FALSE(schema.load_string("bound = 2", "f.toml"));
  REQUIRE(s.bound);
  CHECK(*s.bound == 2.0);
  CHECK(schema.value("bound") == "2.0");
  CHECK(schema.load_string("bound = nan", "f.toml") == "f.toml: bound: must be a number of N in [-10, 10], got nan");
  CHECK(schema.load_string("bound = 11", "f.toml") == "f.toml: bound: must be a number of N in [-10, 10], got 11");
  CHECK(*s.bound == 2.0);
}

TEST_CASE("a text kept as another type: its own parse, a text's checks, and a print that reads back",
          "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  CHECK(schema.value("pin") == "'4'");
  REQUIRE_FALSE(schema.load_string("pin = \"\"", "f.toml"));
  CHECK_FALSE(s.pin);
  CHECK(schema.value("pin") == "''");
  REQUIRE_FALSE(schema.load_assignment("pin=\"12\"", "--set"));
  CHECK(s.pin == 12u);
  CHECK(schema.value_text("pin") == "12");
  CHECK(schema.load_string("pin = \"x\"", "f.toml") == "f.toml: pin: not a pin number");
  CHECK(schema.load_string("pin = 3", "f.toml") == "f.toml: pin: must be a string, got an integer");
  CHECK(schema.load_string("pin = \"1\\u00002\"", "f.toml") == "f.toml: pin: must not contain a NUL byte");
  CHECK(s.pin == 12u);
  Settings again;
  auto reread = schema_for(again);
  REQUIRE_FALSE(reread.load_string(schema.print(), "printed.toml"));
  CHECK(again.pin == 12u);
  CHECK(reread.print() == schema.print());
}

TEST_CASE("a number in a half-open range, named in its own words", "[program][schema]") {
  Settings s;
  auto schema = schema_for(s);
  REQUIRE_FALSE(schema.load_string("cutoff_hz = 499.9", "f.toml"));
  CHECK(s.cutoff_hz == 499.9);
  CHECK(schema.print().find("cutoff_hz = 499.9  # Hz: a cut-off\n") != std::string::npos);
  CHECK(schema.load_string("cutoff_hz = 500", "f.toml") ==
        "f.toml: cutoff_hz: must be a cut-off in Hz in [0, 500), got 500");
  CHECK(schema.load_assignment("cutoff_hz=-1", "--set") ==
        "--set: cutoff_hz: must be a cut-off in Hz in [0, 500), got -1");
  CHECK(schema.load_string("cutoff_hz = \"1\"", "f.toml") == "f.toml: cutoff_hz: must be a number, got a string");
  CHECK(s.cutoff_hz == 499.9);
  REQUIRE_FALSE(schema.load_string("cutoff_hz = 0", "f.toml"));
  CHECK(s.cutoff_hz == 0.0);
}
