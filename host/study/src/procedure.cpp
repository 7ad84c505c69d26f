#include "lever/study/procedure.hpp"

#include <array>
#include <utility>

namespace lever::study {
namespace {

constexpr std::array<std::pair<Direction, std::string_view>, 3> kDirections{
    {{Direction::both, "both"}, {Direction::velocity, "velocity"}, {Direction::force, "force"}}};
constexpr std::array<std::pair<Kind, std::string_view>, 4> kKinds{{{Kind::familiarization, "familiarization"},
                                                                   {Kind::briefing, "briefing"},
                                                                   {Kind::three_ifc, "3ifc"},
                                                                   {Kind::rating, "rating"}}};

template <typename Table, typename E>
std::string_view lookup(const Table& table, E e) {
  for (const auto& [value, text] : table)
    if (value == e) return text;
  return "?";
}

template <typename E, typename Table>
std::optional<E> lookup_name(const Table& table, std::string_view s) {
  for (const auto& [value, text] : table)
    if (text == s) return value;
  return std::nullopt;
}

}  // namespace

std::string_view name(Direction d) { return lookup(kDirections, d); }
std::string_view name(Kind k) { return lookup(kKinds, k); }
std::optional<Direction> direction_named(std::string_view s) { return lookup_name<Direction>(kDirections, s); }
std::optional<Kind> kind_named(std::string_view s) { return lookup_name<Kind>(kKinds, s); }

}  // namespace lever::study
