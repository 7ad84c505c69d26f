#pragma once
// Named choices for an option (--scenario wall-tap): help and errors list the names in their order,
// "wall-tap, free-motion, press-hold", and nothing else (CLI11's CheckedTransformer prints its map,
// "{free-motion->1,...}", and cuts it at an enumerator whose value is 0 printed as a NUL byte).
#include <CLI/CLI.hpp>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "lever/program/text.hpp"

namespace lever::program {

template <typename E>
using Choices = std::vector<std::pair<std::string, E>>;

// An option's choices from the enum's own table and spelling (codec::kAllModes and codec::name, say), so that the
// names are written once, next to the type.
template <typename E, std::size_t N, typename NameOf>
Choices<E> choices_of(const E (&all)[N], NameOf name_of) {
  Choices<E> choices;
  for (const E e : all) choices.emplace_back(std::string(name_of(e)), e);
  return choices;
}

// The same with the enum's name() found next to its type (by argument-dependent lookup): one table, one spelling.
template <typename E, std::size_t N>
Choices<E> choices_of(const E (&all)[N]) {
  return choices_of(all, [](E e) { return name(e); });
}

template <typename E>
std::string choice_names(const Choices<E>& choices) {
  std::string names;
  for (std::size_t i = 0; i < choices.size(); ++i)
    names += (i == 0                    ? ""
              : i + 1 == choices.size() ? (choices.size() == 2 ? " or " : ", or ")
                                        : ", ") +
             choices[i].first;
  return names;
}

// A transform for an enum option: the name (case-insensitive) becomes the enumerator's number, which CLI11
// then converts to the enum.
template <typename E>
CLI::Validator one_of(const Choices<E>& choices) {
  const std::string names = choice_names(choices);
  CLI::Validator v(
      [choices, names](std::string& text) -> std::string {
        for (const auto& [name, value] : choices)
          if (CLI::detail::to_lower(name) == CLI::detail::to_lower(text)) {
            text = std::to_string(static_cast<long long>(value));
            return {};
          }
        return "must be one of " + names + ", got '" + printable(text) + "'";
      },
      [&choices] {
        std::string list;
        for (const auto& [name, value] : choices) list += (list.empty() ? "{" : ", ") + name;
        return list + "}";
      }());
  return v;
}

}  // namespace lever::program
