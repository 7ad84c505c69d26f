#include "allow_list.hpp"

#include <fmt/format.h>

#include <charconv>

#include "lever/protocol/messages.hpp"
#include "shown_value.hpp"

namespace lever::bridge {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::uint32_t parse_id(std::string_view text, std::string_view item) {
  text = trim(text);
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) text.remove_prefix(2);
  std::uint32_t id = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), id, 16);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw std::invalid_argument(fmt::format("allow-list item '{}': '{}' is not a hexadecimal id", shown_value(item, 40),
                                            shown_value(text, 40)));
  if (id > protocol::kMaxStandardId)
    throw std::invalid_argument(
        fmt::format("allow-list item '{}': 0x{:X} is beyond 11 bits (0x7FF)", shown_value(item, 40), id));
  return id;
}

}  // namespace

AllowList AllowList::parse(std::string_view text) {
  AllowList list;
  if (trim(text).empty()) throw std::invalid_argument("allow-list is empty");
  while (!text.empty()) {
    const auto comma = text.find(',');
    const auto item = trim(text.substr(0, comma));
    text = comma == std::string_view::npos ? std::string_view{} : text.substr(comma + 1);
    if (item.empty()) throw std::invalid_argument("allow-list has an empty item (two commas?)");
    const auto dash = item.find('-');
    const std::uint32_t first = parse_id(item.substr(0, dash), item);
    const std::uint32_t last = dash == std::string_view::npos ? first : parse_id(item.substr(dash + 1), item);
    if (last < first)
      throw std::invalid_argument(fmt::format("allow-list item '{}': range runs backwards", shown_value(item, 40)));
    for (std::uint32_t id = first; id <= last; ++id) list.ids_.set(id);
  }
  return list;
}

AllowList AllowList::lever_protocol() {
  // Every identifier of the message set, written as the option would take it.
  std::string ranges;
  for (const auto& m : protocol::kMessageSet)
    ranges += fmt::format("{}0x{:X}-0x{:X}", ranges.empty() ? "" : ",", m.base, m.base + protocol::id_count(m) - 1);
  return parse(ranges);
}

std::string AllowList::describe() const {
  std::string out;
  for (std::uint32_t id = 0; id <= protocol::kMaxStandardId;) {
    if (!ids_.test(id)) {
      ++id;
      continue;
    }
    std::uint32_t last = id;
    while (last + 1 <= protocol::kMaxStandardId && ids_.test(last + 1)) ++last;
    out += fmt::format("{}0x{:03X}", out.empty() ? "" : ",", id);
    if (last != id) out += fmt::format("-0x{:03X}", last);
    id = last + 1;
  }
  return out;
}

}  // namespace lever::bridge
