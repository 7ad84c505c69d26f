#pragma once
// The subject's answers as the runner reads them: one a line, from a terminal, a pipe or a FIFO (docs/study.md,
// "Answers from a program").
#include <cstddef>
#include <deque>
#include <optional>
#include <string>
#include <string_view>

namespace lever::study {

struct AnswerLine {
  std::string text;       // without its newline (and a terminal's carriage return); cut at kMaxAnswerLine bytes
  bool too_long = false;  // the line ran past kMaxAnswerLine: a bad answer, whatever it starts with
};

// An answer is "1" to "10" or an Enter; a line this long is no answer, and keeping no more of it bounds what a
// line without end (a key held down, a program gone wrong) can take of the runner's memory.
inline constexpr std::size_t kMaxAnswerLine = 64;

class AnswerLines {
 public:
  // Bytes as read; any number of lines, or part of one.
  void feed(std::string_view bytes);
  // The input ended: a last line without its newline still counts.
  void end();
  bool ended() const { return ended_; }
  // The oldest whole line not yet taken.
  std::optional<AnswerLine> take();
  // The bytes held: at most kMaxAnswerLine of the line under way, plus the whole lines not yet taken.
  std::size_t held() const;

 private:
  void finish_line();
  std::deque<AnswerLine> lines_;
  AnswerLine partial_;
  bool ended_ = false;
};

}  // namespace lever::study
