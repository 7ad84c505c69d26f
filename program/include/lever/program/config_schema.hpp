#pragma once
// One list of fields per configuration serves loading, validation, printing and the docs (as moteus's
// Serialize does): a TOML file and `--check-config` cannot drift apart. Each field knows its dotted key, its
// unit, its range and a line of documentation; loading reports the file, the key and the problem.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#ifndef TOML_EXCEPTIONS
#define TOML_EXCEPTIONS 1
#endif
#include <toml++/toml.h>

namespace lever::program {

struct Bounds;  // numbers.hpp

class ConfigSchema {
 public:
  // A choice's names and values, e.g. {{"hsi", Role::hsi}, {"top", Role::top}}.
  template <typename E>
  using Choices = std::vector<std::pair<std::string, E>>;
  // A field's load stores the value or says what is wrong with it; its print gives the value as TOML, or nothing
  // while the value is unset (an optional one the file left out), which print() shows as a comment.
  using Load = std::function<std::optional<std::string>(const toml::node&)>;
  using Print = std::function<std::optional<std::string>()>;
  // Whether a string may be "": an empty interface or address is a mistake, an empty index line means none.
  // A text that refuses "" and holds it is unset (printed as a comment, as an unset optional is).
  enum class Empty { allowed, refused };

  void number(std::string key, double& value, double lo, double hi, std::string unit, std::string doc);
  // A range that may be open at an end (a cut-off below Nyquist) and names its values itself ("a fraction"): a key
  // that is also an option, refused in the option's words.
  void number(std::string key, double& value, const Bounds& bounds, std::string unit, std::string doc);
  // Whole numbers: a TOML integer, or a float with no fractional part, in [lo, hi]. Int is any arithmetic type
  // that holds the range (a bit rate kept in a double is still whole in the file).
  template <typename Int>
  void integer(std::string key, Int& value, std::int64_t lo, std::int64_t hi, std::string unit, std::string doc) {
    add({std::move(key), std::move(unit), std::move(doc), load_integer<Int>(value, lo, hi),
         [&value] { return std::to_string(static_cast<std::int64_t>(value)); }});
  }
  // The same, for a value the program decides while the file leaves it out (a random id): printed as a comment
  // while unset, and value() gives "".
  template <typename Int>
  void integer(std::string key, std::optional<Int>& value, std::int64_t lo, std::int64_t hi, std::string unit,
               std::string doc) {
    add({std::move(key), std::move(unit), std::move(doc), load_integer<Int>(value, lo, hi),
         [&value]() -> std::optional<std::string> {
           if (!value) return std::nullopt;
           return std::to_string(static_cast<std::int64_t>(*value));
         }});
  }
  // A number the program may leave unset; printed as a comment while unset.
  void number(std::string key, std::optional<double>& value, double lo, double hi, std::string unit, std::string doc);
  // A std::chrono duration, in the file a whole number of the duration's own unit (`unit`: its name, "us", "ms"),
  // so that the key's name, its range and the value kept cannot disagree on the unit.
  template <typename Rep, typename Period>
  void duration(std::string key, std::chrono::duration<Rep, Period>& value, std::int64_t lo, std::int64_t hi,
                std::string unit, std::string doc) {
    add({std::move(key), std::move(unit), std::move(doc),
         [&value, lo, hi](const toml::node& n) -> std::optional<std::string> {
           std::int64_t v = 0;
           if (auto e = read_integer(n, lo, hi, v)) return e;
           value = std::chrono::duration<Rep, Period>(static_cast<Rep>(v));
           return std::nullopt;
         },
         [&value] { return std::to_string(static_cast<std::int64_t>(value.count())); }});
  }
  void boolean(std::string key, bool& value, std::string doc);
  void text(std::string key, std::string& value, std::string doc, Empty empty = Empty::allowed);
  // A value the file gives as a string and the program keeps as something else (a GPIO line by name or offset; a
  // line, or none for ""): `from_text` makes the value of the string, `to_text` the string that loads back to it.
  // The string passes a text's checks first; a std::invalid_argument from_text throws is the key's problem.
  template <typename T>
  void text_as(std::string key, T& value, std::function<T(const std::string&)> from_text,
               std::function<std::string(const T&)> to_text, std::string doc) {
    add({std::move(key), "", std::move(doc),
         [&value, from_text = std::move(from_text)](const toml::node& n) -> std::optional<std::string> {
           std::string s;
           if (auto e = read_text_value(n, Empty::allowed, s)) return e;
           try {
             value = from_text(s);
           } catch (const std::invalid_argument& e) {
             return std::string(e.what());
           }
           return std::nullopt;
         },
         [&value, to_text = std::move(to_text)] { return quoted(to_text(value)); }});
  }
  // A string with a syntax or a meaning of its own (an id list, a path): `store(text, file)` turns it into the
  // configuration's value, `file` being the file the string was read from (empty for a value from elsewhere, such
  // as --set), for what is relative to it; a std::invalid_argument it throws is the key's problem. An empty string
  // is refused before `store` sees it.
  using Store = std::function<void(const std::string& text, const std::filesystem::path& file)>;
  void parsed_text(std::string key, std::string doc, Store store, Print print);
  // Anything else (a number kept in other units, one key that sets two values), loaded, refused and printed as
  // the fields above are. The read_* functions give `load` the fields' own checks and words.
  void custom(std::string key, std::string unit, std::string doc, Load load, Print print);
  template <typename E>
  void choice(std::string key, E& value, Choices<E> choices, std::string doc) {
    std::string names;
    for (const auto& [name, v] : choices) names += (names.empty() ? "" : ", ") + name;
    add({std::move(key), "", std::move(doc) + " (" + names + ")",
         [&value, choices, names](const toml::node& n) -> std::optional<std::string> {
           std::string s;
           if (auto e = read_text(n, s)) return e;
           for (const auto& [name, v] : choices)
             if (name == s) {
               value = v;
               return std::nullopt;
             }
           return "must be one of " + names + ", got '" + printable(s) + "'";
         },
         [&value, choices] {
           for (const auto& [name, v] : choices)
             if (v == value) return "\"" + name + "\"";
           return std::string("\"?\"");
         }});
  }

  // Loads a TOML file over the current values. Returns "FILE: KEY: problem" (or "FILE:LINE: problem" for a
  // syntax error) on the first problem: unknown keys, wrong types, values out of range, NaN. Keys before the
  // problem may already be set: load into a scratch configuration and keep it only on success.
  std::optional<std::string> load_file(const std::string& path);
  std::optional<std::string> load_string(std::string_view text, const std::string& source_name);
  // One key's value from elsewhere (a command-line option), through the same check as in a file. Returns
  // "SOURCE: KEY: problem" on a problem.
  std::optional<std::string> load_value(const std::string& key, const toml::node& value, const std::string& source);

  // Every problem of a file rather than the first: each key that loads is kept, each that does not is listed
  // ("FILE: KEY: problem", the key also apart; an empty key for a problem of the whole file, which then loads
  // nothing). For a reader that needs some keys only and must go on whatever else is wrong (--motor-off).
  struct KeyProblem {
    std::string key;
    std::string message;
  };
  std::vector<KeyProblem> load_file_each(const std::string& path);
  std::vector<KeyProblem> load_string_each(std::string_view text, const std::string& source_name);
  std::vector<KeyProblem> load_table_each(const toml::table& t, const std::string& source_name);

  // A file as TOML, for a reader that must also see which keys it holds, not only their values (a key left out
  // is a default, which --motor-off must not take for a motor's name). `error`: the read's or the syntax's
  // ("FILE:LINE: problem"), the table then empty.
  struct Parsed {
    toml::table table;
    std::string error;
  };
  static Parsed parse_file(const std::string& path);

  // The dotted keys that start with `prefix`, in the schema's order.
  std::vector<std::string> keys(std::string_view prefix) const;

  // "KEY=VALUE" from elsewhere (a command line's --set), VALUE a TOML value, through the same check as in a file.
  // Returns "SOURCE: KEY: problem", or "SOURCE: 'TEXT': ..." when it is no KEY=VALUE or VALUE no TOML value.
  std::optional<std::string> load_assignment(std::string_view assignment, const std::string& source);

  // One key's effective value as a TOML value ("tcp" quoted, 25, true; "" while an optional one is unset);
  // nothing for a key the schema lacks.
  std::optional<std::string> value(std::string_view key) const;
  // The same for a shell: a string without its quotes, every other value as its TOML text.
  std::optional<std::string> value_text(std::string_view key) const;

  // The effective configuration as a TOML document, every key with its unit and documentation; with a prefix
  // ("board.motor."), only the keys that start with it.
  std::string print(std::string_view prefix = {}) const;

  // The fields' checks, for a custom load: each stores into `out` or returns the problem, in the fields' words.
  static std::optional<std::string> read_number(const toml::node& n, double lo, double hi, const std::string& unit,
                                                double& out);
  static std::optional<std::string> read_number(const toml::node& n, const Bounds& bounds, double& out);
  static std::optional<std::string> read_integer(const toml::node& n, std::int64_t lo, std::int64_t hi,
                                                 std::int64_t& out);
  static std::optional<std::string> read_text(const toml::node& n, std::string& out);
  // The fields' printing, for a custom print: a string quoted and escaped, a number that stays a TOML float.
  static std::string quoted(std::string_view s);
  static std::string number_text(double v);

 private:
  // Both integer fields load alike; `target` is the value or its std::optional.
  template <typename Int, typename Target>
  static std::function<std::optional<std::string>(const toml::node&)> load_integer(Target& target, std::int64_t lo,
                                                                                   std::int64_t hi) {
    return [&target, lo, hi](const toml::node& n) -> std::optional<std::string> {
      std::int64_t v = 0;
      if (auto e = read_integer(n, lo, hi, v)) return e;
      target = static_cast<Int>(v);
      return std::nullopt;
    };
  }
  struct Field {
    std::string key, unit, doc;
    Load load;
    Print print;
  };
  void add(Field f);
  std::string unknown_key(const toml::table& t, const std::string& key, const std::string& source) const;
  static std::optional<std::string> read_text_value(const toml::node& n, Empty empty, std::string& out);
  static std::string printable(std::string_view s);
  // TEXT read as one TOML value (as a file's "key = TEXT" would be); nothing when it is none.
  static std::optional<toml::table> parse_value(std::string_view text);

  std::vector<Field> fields_;
  std::map<std::string, std::size_t, std::less<>> index_;
};

}  // namespace lever::program
