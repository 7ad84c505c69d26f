#include "lever/study/answer_lines.hpp"

namespace lever::study {

void AnswerLines::feed(std::string_view bytes) {
  for (const char c : bytes) {
    if (c == '\n') {
      finish_line();
    } else if (partial_.text.size() < kMaxAnswerLine) {
      partial_.text.push_back(c);
    } else {
      partial_.too_long = true;
    }
  }
}

void AnswerLines::end() {
  if (ended_) return;
  ended_ = true;
  if (!partial_.text.empty() || partial_.too_long) finish_line();
}

void AnswerLines::finish_line() {
  if (!partial_.too_long && !partial_.text.empty() && partial_.text.back() == '\r') partial_.text.pop_back();
  lines_.push_back(std::move(partial_));
  partial_ = {};
}

std::optional<AnswerLine> AnswerLines::take() {
  if (lines_.empty()) return std::nullopt;
  AnswerLine line = std::move(lines_.front());
  lines_.pop_front();
  return line;
}

std::size_t AnswerLines::held() const {
  std::size_t n = partial_.text.size();
  for (const auto& l : lines_) n += l.text.size();
  return n;
}

}  // namespace lever::study
