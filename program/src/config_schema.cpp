#include "lever/program/config_schema.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "lever/program/config_file.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/text.hpp"

namespace lever::program {
namespace {

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    default:
      return "a date or time";
  }
}

// Dotted keys of every leaf value in a table (arrays count as leaves).
void collect_keys(const toml::table& t, const std::string& prefix, std::vector<std::string>& out) {
  for (const auto& [k, v] : t) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (const auto* sub = v.as_table()) {
      collect_keys(*sub, key, out);
    } else {
      out.push_back(key);
    }
  }
}

}  // namespace

// A key the schema does not know may still be a known name of the wrong type: a table's name given a value
// (`encoder = [...]`), or a value's name given a table (`[lever.role]`). Said as the type it should be, since
// "unknown key" sends the user looking for a misspelling that is not there.
std::string ConfigSchema::unknown_key(const toml::table& t, const std::string& key, const std::string& source) const {
  for (auto dot = key.find('.'); dot != std::string::npos; dot = key.find('.', dot + 1)) {
    const std::string prefix = key.substr(0, dot);
    if (const auto it = index_.find(prefix); it != index_.end()) {
      const auto e = fields_[it->second].load(*t.at_path(prefix).node());
      return fmt::format("{}: {}: {}", source, prefix, e.value_or("must not be a table"));
    }
  }
  const std::string table = key + ".";
  for (const auto& f : fields_)
    if (f.key.starts_with(table))
      return fmt::format("{}: {}: must be a table ([{}]), got {}", source, printable(key), printable(key),
                         type_name(*t.at_path(key).node()));
  return fmt::format("{}: {}: unknown key", source, printable(key));
}

void ConfigSchema::add(Field f) {
  index_.emplace(f.key, fields_.size());
  fields_.push_back(std::move(f));
}

std::string ConfigSchema::printable(std::string_view s) { return program::printable(s); }

std::optional<std::string> ConfigSchema::read_integer(const toml::node& n, std::int64_t lo, std::int64_t hi,
                                                      std::int64_t& out) {
  const auto range = fmt::format("a whole number in [{}, {}]", lo, hi);
  if (const auto* i = n.as_integer()) {
    out = i->get();
  } else if (const auto* f = n.as_floating_point()) {
    const double v = f->get();
    if (!std::isfinite(v) || v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
      return fmt::format("must be {}, got {}", range, v);
    out = static_cast<std::int64_t>(v);
  } else {
    return "must be " + range + ", got " + type_name(n);
  }
  if (out < lo || out > hi) return fmt::format("must be {}, got {}", range, out);
  return std::nullopt;
}

std::optional<std::string> ConfigSchema::read_text(const toml::node& n, std::string& out) {
  const auto* s = n.as_string();
  if (!s) return "must be a string, got " + type_name(n);
  out = s->get();
  return std::nullopt;
}

// A NUL would cut the string short wherever it becomes a C string (a path, an interface name).
std::optional<std::string> ConfigSchema::read_text_value(const toml::node& n, Empty empty, std::string& out) {
  std::string s;
  if (auto e = read_text(n, s)) return e;
  if (s.find('\0') != std::string::npos) return "must not contain a NUL byte";
  if (empty == Empty::refused && s.empty()) return "must not be empty";
  out = std::move(s);
  return std::nullopt;
}

std::optional<std::string> ConfigSchema::read_number(const toml::node& n, double lo, double hi, const std::string& unit,
                                                     double& out) {
  const std::string what = unit.empty() ? "a number" : "a number of " + unit;
  return read_number(n, Bounds{lo, hi, false, false, what}, out);
}

std::optional<std::string> ConfigSchema::read_number(const toml::node& n, const Bounds& bounds, double& out) {
  double v = 0.0;
  if (const auto* f = n.as_floating_point()) {
    v = f->get();
  } else if (const auto* i = n.as_integer()) {
    v = static_cast<double>(i->get());
  } else {
    return "must be a number, got " + type_name(n);
  }
  // The same check, and the same words, as the programs' numeric options.
  if (auto e = program::check_number(v, bounds)) return e;
  out = v;
  return std::nullopt;
}

std::string ConfigSchema::quoted(std::string_view s) {
  std::ostringstream out;
  out << toml::value<std::string>(std::string(s));
  return out.str();
}

std::string ConfigSchema::number_text(double v) {
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // stays a TOML float
  return s;
}

void ConfigSchema::number(std::string key, double& value, double lo, double hi, std::string unit, std::string doc) {
  add({std::move(key), unit, std::move(doc),
       [&value, lo, hi, unit](const toml::node& n) { return read_number(n, lo, hi, unit, value); },
       [&value] { return number_text(value); }});
}

void ConfigSchema::number(std::string key, double& value, const Bounds& bounds, std::string unit, std::string doc) {
  add({std::move(key), std::move(unit), std::move(doc),
       // The load runs after the caller's text for bounds.what may be gone: it keeps a copy.
       [&value, bounds, what = std::string(bounds.what)](const toml::node& n) {
         Bounds own = bounds;
         own.what = what;
         return read_number(n, own, value);
       },
       [&value] { return number_text(value); }});
}

void ConfigSchema::number(std::string key, std::optional<double>& value, double lo, double hi, std::string unit,
                          std::string doc) {
  add({std::move(key), unit, std::move(doc),
       [&value, lo, hi, unit](const toml::node& n) -> std::optional<std::string> {
         double v = 0.0;
         if (auto e = read_number(n, lo, hi, unit, v)) return e;
         value = v;
         return std::nullopt;
       },
       [&value]() -> std::optional<std::string> {
         if (!value) return std::nullopt;
         return number_text(*value);
       }});
}

void ConfigSchema::boolean(std::string key, bool& value, std::string doc) {
  add({std::move(key), "", std::move(doc),
       [&value](const toml::node& n) -> std::optional<std::string> {
         const auto* b = n.as_boolean();
         if (!b) return "must be true or false, got " + type_name(n);
         value = b->get();
         return std::nullopt;
       },
       [&value] { return std::string(value ? "true" : "false"); }});
}

void ConfigSchema::text(std::string key, std::string& value, std::string doc, Empty empty) {
  add({std::move(key), "", std::move(doc),
       [&value, empty](const toml::node& n) { return read_text_value(n, empty, value); },
       // A text that refuses "" holds it only while unset: printed, it would not load back.
       [&value, empty]() -> std::optional<std::string> {
         if (empty == Empty::refused && value.empty()) return std::nullopt;
         return quoted(value);
       }});
}

void ConfigSchema::parsed_text(std::string key, std::string doc, Store store, Print print) {
  add({std::move(key), "", std::move(doc),
       [store = std::move(store)](const toml::node& n) -> std::optional<std::string> {
         std::string s;
         if (auto e = read_text_value(n, Empty::refused, s)) return e;
         // toml++ keeps, on every node, the source name the document was parsed under: load_file's path.
         const auto& file = n.source().path;
         try {
           store(s, file ? std::filesystem::path(*file) : std::filesystem::path());
         } catch (const std::invalid_argument& e) {
           return std::string(e.what());
         }
         return std::nullopt;
       },
       std::move(print)});
}

void ConfigSchema::custom(std::string key, std::string unit, std::string doc, Load load, Print print) {
  add({std::move(key), std::move(unit), std::move(doc), std::move(load), std::move(print)});
}

std::optional<std::string> ConfigSchema::load_string(std::string_view text, const std::string& source_name) {
  toml::table t;
  try {
    t = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    return fmt::format("{}:{}: {}", source_name, e.source().begin.line, e.description());
  }
  std::vector<std::string> keys;
  collect_keys(t, "", keys);
  for (const auto& key : keys)
    if (index_.find(key) == index_.end()) return unknown_key(t, key, source_name);
  for (const auto& f : fields_) {
    const auto node = t.at_path(f.key);
    if (!node) continue;
    if (auto e = f.load(*node.node())) return fmt::format("{}: {}: {}", source_name, f.key, *e);
  }
  return std::nullopt;
}

std::optional<std::string> ConfigSchema::load_file(const std::string& path) {
  const auto file = program::read_config_file(path);
  if (!file.error.empty()) return file.error;
  return load_string(file.text, path);
}

std::vector<ConfigSchema::KeyProblem> ConfigSchema::load_file_each(const std::string& path) {
  const auto parsed = parse_file(path);
  if (!parsed.error.empty()) return {{"", parsed.error}};
  return load_table_each(parsed.table, path);
}

std::vector<ConfigSchema::KeyProblem> ConfigSchema::load_string_each(std::string_view text,
                                                                     const std::string& source_name) {
  toml::table t;
  try {
    t = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    return {{"", fmt::format("{}:{}: {}", source_name, e.source().begin.line, e.description())}};
  }
  return load_table_each(t, source_name);
}

std::vector<ConfigSchema::KeyProblem> ConfigSchema::load_table_each(const toml::table& t,
                                                                    const std::string& source_name) {
  std::vector<KeyProblem> problems;
  std::vector<std::string> keys;
  collect_keys(t, "", keys);
  for (const auto& key : keys)
    if (index_.find(key) == index_.end())
      problems.push_back({key, fmt::format("{}: {}: unknown key", source_name, printable(key))});
  for (const auto& f : fields_) {
    const auto node = t.at_path(f.key);
    if (!node) continue;
    if (auto e = f.load(*node.node())) problems.push_back({f.key, fmt::format("{}: {}: {}", source_name, f.key, *e)});
  }
  return problems;
}

ConfigSchema::Parsed ConfigSchema::parse_file(const std::string& path) {
  Parsed out;
  const auto file = program::read_config_file(path);
  if (!file.error.empty()) {
    out.error = file.error;
    return out;
  }
  try {
    out.table = toml::parse(file.text, path);
  } catch (const toml::parse_error& e) {
    out.error = fmt::format("{}:{}: {}", path, e.source().begin.line, e.description());
  }
  return out;
}

std::vector<std::string> ConfigSchema::keys(std::string_view prefix) const {
  std::vector<std::string> out;
  for (const auto& f : fields_)
    if (f.key.starts_with(prefix)) out.push_back(f.key);
  return out;
}

std::optional<std::string> ConfigSchema::load_assignment(std::string_view assignment, const std::string& source) {
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos || eq == 0)
    return fmt::format("{}: '{}': expected KEY=VALUE, VALUE a TOML value (\"vcan0\", 0.05, true)", source,
                       printable(assignment));
  const std::string key(assignment.substr(0, eq));
  const std::string text(assignment.substr(eq + 1));
  const auto parsed = parse_value(text);
  if (!parsed)
    return fmt::format("{}: {}: '{}' is no TOML value (a string needs its quotes: \"vcan0\")", source, printable(key),
                       printable(text));
  return load_value(key, *parsed->get("v"), source);
}

std::optional<toml::table> ConfigSchema::parse_value(std::string_view text) {
  try {
    return toml::parse("v = " + std::string(text));
  } catch (const toml::parse_error&) {
    return std::nullopt;
  }
}

std::optional<std::string> ConfigSchema::value_text(std::string_view key) const {
  const auto printed = value(key);
  if (!printed) return std::nullopt;
  // The schema's own printing always parses; a string comes back bare.
  const auto parsed = parse_value(*printed);
  if (const auto bare = parsed ? (*parsed)["v"].value<std::string>() : std::nullopt) return *bare;
  return printed;
}

std::optional<std::string> ConfigSchema::value(std::string_view key) const {
  const auto it = index_.find(key);
  if (it == index_.end()) return std::nullopt;
  return fields_[it->second].print().value_or("");
}

std::optional<std::string> ConfigSchema::load_value(const std::string& key, const toml::node& value,
                                                    const std::string& source) {
  const auto it = index_.find(key);
  if (it == index_.end()) return fmt::format("{}: {}: unknown key", source, printable(key));
  if (auto e = fields_[it->second].load(value)) return fmt::format("{}: {}: {}", source, key, *e);
  return std::nullopt;
}

std::string ConfigSchema::print(std::string_view prefix) const {
  std::string out;
  std::string section;
  for (const auto& f : fields_) {
    if (!f.key.starts_with(prefix)) continue;
    const auto dot = f.key.rfind('.');
    const std::string table = dot == std::string::npos ? "" : f.key.substr(0, dot);
    const std::string name = dot == std::string::npos ? f.key : f.key.substr(dot + 1);
    if (table != section) {
      out += fmt::format("{}[{}]\n", out.empty() ? "" : "\n", table);
      section = table;
    }
    const auto value = f.print();
    const std::string unit = f.unit.empty() ? "" : f.unit + ": ";
    // An unset value stays out of the document, which then reads back as the configuration it shows.
    if (value) {
      out += fmt::format("{} = {}  # {}{}\n", name, *value, unit, f.doc);
    } else {
      out += fmt::format("# {} (unset)  # {}{}\n", name, unit, f.doc);
    }
  }
  return out;
}

}  // namespace lever::program
