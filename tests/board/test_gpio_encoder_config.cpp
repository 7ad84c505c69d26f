// The encoder's config: line references, validation messages that name the field, and open() refusing to
// make an object out of a bad config or a missing chip (the real chip is tested in the kernel rig).
#include <catch2/catch.hpp>
#include <string>

#include "lever/board/gpio_encoder.hpp"

using lever::board::GpioEncoder;
using lever::board::GpioEncoderConfig;
using lever::board::LineRef;

namespace {

GpioEncoderConfig good() {
  GpioEncoderConfig c;
  c.chip = "gpiochip0";
  c.line_a = LineRef::parse("ENC_A");
  c.line_b = LineRef::parse("ENC_B");
  c.line_z = LineRef::parse("7");
  return c;
}

bool mentions(const std::vector<std::string>& problems, const std::string& text) {
  for (const auto& p : problems)
    if (p.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("a line given as digits is an offset, anything else a name") {
  CHECK(LineRef::parse("12").is_offset());
  CHECK(LineRef::parse("12").offset_value() == 12);
  CHECK_FALSE(LineRef::parse("12a").is_offset());
  CHECK(LineRef::parse("ENC_A").name_value() == "ENC_A");
  CHECK_FALSE(LineRef::parse("99999999999999999999").is_offset());
  CHECK(LineRef::parse("3").describe() == "offset 3");
  CHECK(LineRef::parse("ENC_A").describe() == "\"ENC_A\"");
}

TEST_CASE("a line keeps the text it was given, and is the same line however its offset was written") {
  CHECK(LineRef::parse("017").text() == "017");
  CHECK(LineRef::parse("017") == LineRef::parse("17"));
  CHECK(LineRef::parse("017") == LineRef::offset(17));
  CHECK(LineRef::offset(17).text() == "17");
  CHECK(LineRef::parse("ENC_A").text() == "ENC_A");
  CHECK(LineRef::parse("").text().empty());
  CHECK(LineRef::parse("99999999999999999999").text() == "99999999999999999999");
}

TEST_CASE("a good config validates") { CHECK(good().validate().empty()); }

TEST_CASE("each problem names its field") {
  auto c = good();
  c.chip.clear();
  CHECK(mentions(c.validate(), "chip: empty"));

  c = good();
  c.line_b = LineRef::name("");
  CHECK(mentions(c.validate(), "line_b: empty name"));

  c = good();
  c.line_b = LineRef::parse("ENC_A");
  CHECK(mentions(c.validate(), "line_b: the same line as line_a"));

  c = good();
  c.line_z = LineRef::parse("ENC_B");
  CHECK(mentions(c.validate(), "line_z: the same line as line_b"));

  c = good();
  c.consumer = std::string(32, 'x');
  CHECK(mentions(c.validate(), "consumer: 32 characters"));

  c = good();
  c.edge_latency_us = 2'000;
  CHECK(mentions(c.validate(), "edge_latency_us"));

  c = good();
  c.chip.clear();
  c.consumer.clear();
  CHECK(c.validate().size() == 2);
}

TEST_CASE("open refuses a bad config with every problem in one message") {
  auto c = good();
  c.chip.clear();
  c.consumer.clear();
  const auto r = GpioEncoder::open(c);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("chip: empty") != std::string::npos);
  CHECK(r.error().message.find("consumer: empty") != std::string::npos);
}

TEST_CASE("open names the chip it cannot find") {
  auto c = good();
  c.chip = "/dev/gpiochip-that-is-not-there";
  const auto r = GpioEncoder::open(c);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("gpiochip-that-is-not-there") != std::string::npos);
  CHECK(r.error().errno_value != 0);

  c.chip = "no-such-label";
  CHECK_FALSE(GpioEncoder::open(c).ok());
}
