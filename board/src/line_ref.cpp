#include "lever/board/line_ref.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>

namespace lever::board {

LineRef LineRef::parse(std::string_view text) {
  const bool digits = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
  });
  if (digits) {
    unsigned value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec == std::errc{} && end == text.data() + text.size()) {
      LineRef line(value);
      line.offset_text_ = text;
      return line;
    }
  }
  // Too many digits for an offset is no offset either; open() then reports no line of that name.
  return name(std::string(text));
}

std::string LineRef::text() const {
  if (!is_offset()) return name_value();
  return offset_text_.empty() ? std::to_string(offset_value()) : offset_text_;
}

std::string LineRef::describe() const {
  if (is_offset()) return "offset " + std::to_string(offset_value());
  return "\"" + name_value() + "\"";
}

}  // namespace lever::board
