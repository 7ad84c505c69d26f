// The runner's answers' input: one answer a line, whatever pieces the reads bring, and a line without end bounded
// and refused as an answer rather than held whole (docs/study.md, "Answers from a program").
#include <catch2/catch.hpp>
#include <string>

#include "lever/study/answer_lines.hpp"

namespace {

namespace study = lever::study;

}  // namespace

TEST_CASE("answers: one a line, from reads that split and join lines anyhow", "[unit][study]") {
  study::AnswerLines in;
  in.feed("2\n1");
  auto a = in.take();
  REQUIRE(a);
  CHECK(a->text == "2");
  CHECK_FALSE(a->too_long);
  CHECK_FALSE(in.take());  // "1" has no newline yet
  in.feed("0\r\n\n3\n");
  CHECK(in.take()->text == "10");  // a terminal's carriage return is not part of the answer
  CHECK(in.take()->text.empty());  // Enter alone: an acknowledgement
  CHECK(in.take()->text == "3");
  CHECK_FALSE(in.take());
}

TEST_CASE("answers: a last line without its newline counts once the input ended, and then nothing is left",
          "[unit][study]") {
  study::AnswerLines in;
  in.feed("7");
  CHECK_FALSE(in.take());
  in.end();
  CHECK(in.ended());
  CHECK(in.take()->text == "7");
  CHECK_FALSE(in.take());
  study::AnswerLines empty;
  empty.end();
  CHECK_FALSE(empty.take());
}

TEST_CASE("answers: a line without end is held to the limit, never more, and is a bad answer when it ends",
          "[unit][study]") {
  study::AnswerLines in;
  const std::string block(4096, '1');
  for (int i = 0; i < 1024; ++i) in.feed(block);  // 4 MiB of one line
  CHECK(in.held() <= study::kMaxAnswerLine);
  CHECK_FALSE(in.take());
  in.feed("\n2\n");
  const auto long_line = in.take();
  REQUIRE(long_line);
  CHECK(long_line->too_long);
  // What follows the long line is read as it comes: the next answer is not lost.
  const auto next = in.take();
  REQUIRE(next);
  CHECK_FALSE(next->too_long);
  CHECK(next->text == "2");
}

TEST_CASE("answers: a line of exactly the limit is whole, one byte more is too long", "[unit][study]") {
  study::AnswerLines in;
  in.feed(std::string(study::kMaxAnswerLine, ' ') + "\n" + std::string(study::kMaxAnswerLine + 1, '0') + "\n");
  CHECK_FALSE(in.take()->too_long);
  CHECK(in.take()->too_long);  // zeros that stoi would have read as 0, or after a cut as a valid number
}

TEST_CASE("answers: an input that ends inside a long line gives it as too long", "[unit][study]") {
  study::AnswerLines in;
  in.feed(std::string(study::kMaxAnswerLine * 3, '9'));
  in.end();
  const auto line = in.take();
  REQUIRE(line);
  CHECK(line->too_long);
}
