#pragma once
// A value the user gave, made fit for a one-line message: control bytes shown as '?', and cut to `limit` bytes
// with "..." (a 100 kB option must not become a 100 kB line of stderr). Local to the bridge for now; it belongs
// with the programs' shared support (program/) once that has one.
#include <cstddef>
#include <string>
#include <string_view>

namespace lever::bridge {

inline std::string shown_value(std::string_view text, std::size_t limit = 80) {
  std::string out(text.substr(0, text.size() > limit ? limit - 3 : text.size()));
  for (auto& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = '?';
  }
  if (text.size() > limit) out += "...";
  return out;
}

}  // namespace lever::bridge
