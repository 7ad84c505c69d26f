#pragma once
// A GPIO line as a board's config names it: by its offset on the chip or by its name.
#include <string>
#include <string_view>
#include <variant>

namespace lever::board {

// A line by its offset on the chip or by its name (as the device tree or gpio-line-names give it).
class LineRef {
 public:
  LineRef() = default;
  static LineRef offset(unsigned offset) { return LineRef(offset); }
  static LineRef name(std::string name) { return LineRef(std::move(name)); }
  // All digits: an offset; anything else: a name.
  static LineRef parse(std::string_view text);

  bool is_offset() const noexcept { return std::holds_alternative<unsigned>(ref_); }
  unsigned offset_value() const { return std::get<unsigned>(ref_); }
  const std::string& name_value() const { return std::get<std::string>(ref_); }
  std::string describe() const;  // "offset 3" or "\"ENC_A\"", for messages
  // The line as the config wrote it ("017" for offset 17), so that a config printed back says what its file said.
  std::string text() const;
  // "017" and "17" are one line.
  bool operator==(const LineRef& other) const noexcept { return ref_ == other.ref_; }

 private:
  explicit LineRef(unsigned offset) : ref_(offset) {}
  explicit LineRef(std::string name) : ref_(std::move(name)) {}
  std::variant<unsigned, std::string> ref_{0u};
  std::string offset_text_;  // parse()'s digits for an offset; empty: the offset's own
};

}  // namespace lever::board
