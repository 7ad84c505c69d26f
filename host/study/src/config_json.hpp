#pragma once
// Reading the procedures' configurations from a log's header: a missing field keeps its default, a field of the
// wrong type or out of range is refused by name.
#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "lever/study/procedure.hpp"

namespace lever::study::detail {

inline void require(bool ok, const char* field, const char* what) {
  if (!ok) throw std::invalid_argument(fmt::format("{} must be {}", field, what));
}

template <typename T>
void read(const nlohmann::json& j, const char* field, T& out) {
  if (!j.contains(field)) return;
  try {
    out = j.at(field).get<T>();
  } catch (const nlohmann::json::exception&) {
    throw std::invalid_argument(fmt::format("{} has the wrong type ({})", field, j.at(field).type_name()));
  }
}

inline void read(const nlohmann::json& j, const char* field, Direction& out) {
  std::string text;
  read(j, field, text);
  if (!j.contains(field)) return;
  const auto d = direction_named(text);
  if (!d) throw std::invalid_argument(fmt::format("{} must be both, velocity or force, not '{}'", field, text));
  out = *d;
}

}  // namespace lever::study::detail
