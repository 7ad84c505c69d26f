#include "lever/program/numbers.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include "lever/program/text.hpp"

namespace lever::program {

std::string short_number(double v) {
  // Six significant digits: "0.1", "86400", "65.535", "1e+300", never 309 of them.
  return fmt::format("{:.6g}", v);
}

std::string describe(const Bounds& b) {
  const bool has_lo = std::isfinite(b.lo), has_hi = std::isfinite(b.hi);
  if (has_lo && has_hi)
    return fmt::format("{} in {}{}, {}{}", b.what, b.lo_open ? "(" : "[", short_number(b.lo), short_number(b.hi),
                       b.hi_open ? ")" : "]");
  if (has_lo) return fmt::format("{} {} {}", b.what, b.lo_open ? ">" : ">=", short_number(b.lo));
  if (has_hi) return fmt::format("{} {} {}", b.what, b.hi_open ? "<" : "<=", short_number(b.hi));
  return fmt::format("a finite {}", b.what);
}

std::optional<std::string> check_number(double v, const Bounds& b) {
  const bool below = b.lo_open ? !(v > b.lo) : !(v >= b.lo);
  const bool above = b.hi_open ? !(v < b.hi) : !(v <= b.hi);
  if (!std::isfinite(v) || below || above) return fmt::format("must be {}, got {}", describe(b), short_number(v));
  return std::nullopt;
}

std::optional<std::string> check_number_text(std::string_view text, const Bounds& b) {
  const std::string s(text);  // strtod needs a terminated string
  char* end = nullptr;
  errno = 0;
  const double v = s.empty() ? 0.0 : std::strtod(s.c_str(), &end);
  const bool syntax = !s.empty() && end == s.c_str() + s.size() && s.find_first_of("xXpP") == std::string::npos;
  // Overflow (1e999) is refused as out of range; underflow to a denormal or 0 is a number like any other.
  if (!syntax || !std::isfinite(v) || (errno == ERANGE && std::fabs(v) > 1.0))
    return fmt::format("must be {}, got '{}'", describe(b), printable(text));
  if (check_number(v, b)) return fmt::format("must be {}, got {}", describe(b), printable(text));
  return std::nullopt;
}

std::optional<std::string> check_whole_text(std::string_view text, std::uint64_t lo, std::uint64_t hi,
                                            std::string_view what) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    return fmt::format(
        "must be {} in [{}, {}], got {}", what, lo, hi,
        ec == std::errc() && end == text.data() + text.size() ? std::string(text) : "'" + printable(text) + "'");
  return std::nullopt;
}

CLI::Validator number(Bounds b) {
  // The check runs at parse time, after a caller's text for `what` ("a floor in " + unit) may be gone: it keeps a copy.
  return CLI::Validator(
      [b, what = std::string(b.what)](std::string& text) {
        Bounds own = b;
        own.what = what;
        return check_number_text(text, own).value_or("");
      },
      describe(b));
}

CLI::Validator whole(std::uint64_t lo, std::uint64_t hi, std::string_view what) {
  const std::string name(what);
  return CLI::Validator([lo, hi, name](std::string& text) { return check_whole_text(text, lo, hi, name).value_or(""); },
                        fmt::format("{} in [{}, {}]", name, lo, hi));
}

CLI::Validator seed() { return whole(0, std::numeric_limits<std::uint64_t>::max(), "a seed"); }

}  // namespace lever::program
