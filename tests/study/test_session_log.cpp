// The session log: one record a trial, and a session resumed from it in exactly the state after its last
// complete record, a cut last line ignored with a warning (docs/study.md, "The session log").
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "lever/study/observer.hpp"
#include "lever/study/rating.hpp"
#include "lever/study/session_log.hpp"
#include "lever/study/three_ifc.hpp"

namespace {

namespace study = lever::study;
namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "lever-study-XXXXXX").string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path = pattern;
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool same_trial(const study::Trial& a, const study::Trial& b) {
  return a.kind == b.kind && a.pass == b.pass && a.trial == b.trial && a.p == b.p && a.direction == b.direction &&
         a.carrier == b.carrier && a.intervals == b.intervals;
}

// Runs a 3IFC session for a simulated observer, voiding every seventh trial, writing every record; returns the
// procedure after each record.
std::vector<study::ThreeIfcStaircase> run_session(const fs::path& log, std::uint64_t seed) {
  study::SessionHeader h{"3ifc", "s01", seed, true, study::to_json(study::ThreeIfcConfig{})};
  auto writer = study::SessionLogWriter::create(log.string(), h);
  study::ThreeIfcStaircase s({}, seed);
  const study::WeibullObserver observer{0.12, 3.0, 0.02};
  lever::Rng rng(seed + 1);
  std::vector<study::ThreeIfcStaircase> states;
  int attempt = 0;
  while (!s.done()) {
    const auto t = s.current();
    auto r = study::record_of(t, ++attempt);
    if (attempt % 7 == 0) {
      r.void_reason = "settings not confirmed";
      writer.append(r);
      s.void_trial();
    } else if (t.takes_answer()) {
      r.answer = observer.answer(t, rng);
      r.right = *r.answer == t.carrier;
      writer.append(r);
      s.answer(*r.answer);
    } else {
      writer.append(r);
      s.acknowledge();
    }
    states.push_back(s);
  }
  return states;
}

}  // namespace

TEST_CASE("log: a session resumed from its log after any record is in the state the live session was",
          "[unit][study]") {
  TempDir dir;
  const auto path = dir.path / "s01.jsonl";
  const auto states = run_session(path, 21);
  const auto log = study::read_session_log(path.string());
  CHECK(log.warnings.empty());
  REQUIRE(log.records.size() == states.size());
  CHECK(log.header.simulated);
  CHECK(log.header.seed == 21);
  for (std::size_t k = 0; k < log.records.size(); ++k) {
    auto procedure = study::make_procedure(log.header);
    study::replay(*procedure, {log.records.begin(), log.records.begin() + static_cast<long>(k + 1)});
    auto& resumed = dynamic_cast<study::ThreeIfcStaircase&>(*procedure);
    const auto& live = states[k];
    REQUIRE(resumed.done() == live.done());
    CHECK(resumed.passes().size() == live.passes().size());
    CHECK(resumed.right_in_a_row() == live.right_in_a_row());
    if (!live.done()) CHECK(same_trial(resumed.current(), live.current()));
  }
  const auto resumed_whole = study::resume(log);
  auto& whole = dynamic_cast<study::ThreeIfcStaircase&>(*resumed_whole);
  REQUIRE(whole.done());
  CHECK(whole.threshold() == states.back().threshold());
}

TEST_CASE("log: a last line cut mid-write is ignored with a warning, and the writer resumes after the last whole line",
          "[unit][study]") {
  TempDir dir;
  const auto path = dir.path / "s01.jsonl";
  const auto states = run_session(path, 8);
  const auto whole = slurp(path);
  // Cut inside the record of attempt 10: the log ends after record 9 and the first bytes of record 10.
  std::size_t at = 0;
  for (int line = 0; line < 10; ++line) at = whole.find('\n', at) + 1;  // header + 9 records
  const std::size_t cut = at + 25;
  fs::resize_file(path, cut);

  const auto log = study::read_session_log(path.string());
  REQUIRE(log.warnings.size() == 1);
  CHECK_THAT(log.warnings[0], Catch::Contains("line 11"));
  REQUIRE(log.records.size() == 9);
  CHECK(log.complete_bytes == at);
  auto procedure = study::resume(log);
  CHECK(same_trial(procedure->current(), states[8].current()));

  // Resumed: the cut bytes go, the next record follows the last complete one and the log reads back whole.
  {
    auto writer = study::SessionLogWriter::resume(path.string(), log);
    writer.append(study::record_of(procedure->current(), 10));
  }
  const auto again = study::read_session_log(path.string());
  CHECK(again.warnings.empty());
  CHECK(again.records.size() == 10);

  SECTION("a last line that is whole but not JSON is ignored too") {
    std::ofstream(path, std::ios::app) << "{\"record\":\"tri\n";
    const auto garbled = study::read_session_log(path.string());
    CHECK(garbled.warnings.size() == 1);
    CHECK(garbled.records.size() == 10);
  }
}

TEST_CASE("log: a bad line before the last is an error, not a warning", "[unit][study]") {
  TempDir dir;
  const auto path = dir.path / "s01.jsonl";
  run_session(path, 3);
  auto text = slurp(path);
  const auto second = text.find('\n') + 1;
  text.insert(second, "not json\n");
  std::ofstream(path, std::ios::trunc) << text;
  CHECK_THROWS_AS(study::read_session_log(path.string()), study::SessionLogError);
  CHECK_THROWS_AS(study::parse_session_log("", "empty"), study::SessionLogError);
}

TEST_CASE("log: a log replayed with another seed is refused: its records are not what the procedure presents",
          "[unit][study]") {
  TempDir dir;
  const auto path = dir.path / "s01.jsonl";
  run_session(path, 5);
  auto log = study::read_session_log(path.string());
  log.header.seed = 6;
  CHECK_THROWS_AS(study::resume(log), study::SessionLogError);
}

TEST_CASE("log: directions and kinds are written by the names docs/study.md gives, and read back", "[unit][study]") {
  using lever::study::Direction;
  using lever::study::Kind;
  CHECK(lever::study::name(Direction::velocity) == "velocity");
  CHECK(lever::study::name(Direction::force) == "force");
  CHECK(lever::study::name(Direction::both) == "both");
  CHECK(lever::study::name(Kind::familiarization) == "familiarization");
  CHECK(lever::study::name(Kind::briefing) == "briefing");
  CHECK(lever::study::name(Kind::three_ifc) == "3ifc");
  CHECK(lever::study::name(Kind::rating) == "rating");
  for (const auto d : {Direction::velocity, Direction::force, Direction::both})
    CHECK(lever::study::direction_named(lever::study::name(d)) == d);
  for (const auto k : {Kind::familiarization, Kind::briefing, Kind::three_ifc, Kind::rating})
    CHECK(lever::study::kind_named(lever::study::name(k)) == k);
  CHECK_FALSE(lever::study::direction_named("motion"));
}

TEST_CASE("log: the writer never writes over an existing session", "[unit][study]") {
  TempDir dir;
  const auto path = dir.path / "s01.jsonl";
  run_session(path, 5);
  CHECK_THROWS_AS(study::SessionLogWriter::create(path.string(), {"3ifc", "s01", 5, false, {}}),
                  study::SessionLogError);
}

TEST_CASE("log: a rating session's records round-trip and resume", "[unit][study]") {
  study::RatingRun r({}, 2);
  study::SessionHeader h{"rating", "s02", 2, false, r.config_json()};
  std::string text = study::to_json(h).dump() + "\n";
  int attempt = 0;
  for (int i = 0; i < 8; ++i) {
    const auto t = r.current();
    auto rec = study::record_of(t, ++attempt);
    if (t.takes_answer()) {
      rec.answer = 1 + i % 10;
      r.answer(*rec.answer);
    } else {
      r.acknowledge();
    }
    text += study::to_json(rec).dump() + "\n";
  }
  const auto log = study::parse_session_log(text, "mem");
  const auto procedure = study::resume(log);
  auto& resumed = dynamic_cast<study::RatingRun&>(*procedure);
  CHECK(resumed.ratings().size() == 6);
  CHECK(same_trial(resumed.current(), r.current()));
}

TEST_CASE("log: the runner's fields of a record survive the round trip", "[unit][study]") {
  study::ThreeIfcStaircase s({}, 1);
  s.acknowledge();
  auto r = study::record_of(s.current(), 2);
  r.void_reason = "fault: TOP motor";
  r.intervals[1].start_bus_us = 1'000'000;
  r.intervals[1].end_bus_us = 21'000'000;
  r.intervals[1].frames_velocity = 5012;
  r.intervals[1].frames_force = 1234;
  r.intervals[1].confirmed = {{"hsi", {{"p", 0.025}}}, {"top", {{"p", 0.025}}}};
  const auto back = study::record_from_json(nlohmann::json::parse(study::to_json(r).dump()));
  CHECK(back.void_reason == r.void_reason);
  CHECK(back.carrier == r.carrier);
  REQUIRE(back.intervals.size() == 3);
  CHECK(back.intervals[1].interval == r.intervals[1].interval);
  CHECK(back.intervals[1].start_bus_us == 1'000'000);
  CHECK(back.intervals[1].end_bus_us == 21'000'000);
  CHECK(back.intervals[1].frames_velocity == 5012u);
  CHECK(back.intervals[1].frames_force == 1234u);
  CHECK(back.intervals[1].confirmed == r.intervals[1].confirmed);
  CHECK_FALSE(back.intervals[0].frames_velocity);
  CHECK(back.intervals[0].confirmed.is_null());
}

TEST_CASE("log: a session on a simulated pair names it in its header, other headers read as they always did",
          "[unit][study]") {
  study::SessionHeader h{"3ifc", "hil01", 3, true, study::to_json(study::ThreeIfcConfig{}), nullptr};
  const std::string plain = study::to_json(h).dump();
  CHECK(plain.find("simulator") == std::string::npos);
  CHECK(study::header_from_json(nlohmann::json::parse(plain)).simulator.is_null());
  h.simulator = {{"topology", "one-controller"}, {"gauge_chain", "paper-adc"}, {"seed", 3}};
  const auto back = study::header_from_json(nlohmann::json::parse(study::to_json(h).dump()));
  CHECK(back.simulator == h.simulator);
  auto bad = nlohmann::json::parse(plain);
  bad["simulator"] = "lever-hil";
  CHECK_THROWS_AS(study::header_from_json(bad), study::SessionLogError);
}

TEST_CASE("log: the header's config makes the same procedure; a config out of range is refused", "[unit][study]") {
  study::ThreeIfcConfig c;
  c.step = 0.02;
  c.direction = study::Direction::velocity;
  c.interval_s = 4.0;
  const auto back = study::three_ifc_config_from_json(nlohmann::json::parse(study::to_json(c).dump()));
  CHECK(back.step == 0.02);
  CHECK(back.direction == study::Direction::velocity);
  CHECK(back.interval_s == 4.0);
  CHECK(back.start_p == c.start_p);
  study::RatingConfig rc;
  rc.runs = {study::Direction::force};
  rc.values = {0.0, 0.1};
  const auto rback = study::rating_config_from_json(study::to_json(rc));
  CHECK(rback.runs == rc.runs);
  CHECK(rback.values == rc.values);
  CHECK_THROWS_AS(study::make_procedure({"3ifc", "s", 1, false, {{"step", -1}}}), study::SessionLogError);
  CHECK_THROWS_AS(study::make_procedure({"3ifc", "s", 1, false, {{"direction", "up"}}}), study::SessionLogError);
  CHECK_THROWS_AS(study::make_procedure({"rating", "s", 1, false, {{"values", "none"}}}), study::SessionLogError);
  CHECK_THROWS_AS(study::make_procedure({"staircase", "s", 1, false, {}}), study::SessionLogError);
}
