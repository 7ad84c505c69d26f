#pragma once
// Validated numbers: every numeric option and configuration key is finite, in its range, and refused in its
// own terms ("--p must be a fraction in [0, 1), got -0.1"). The check runs on the text as typed, before CLI11
// converts it, so NaN, infinities, "1e300" for a value that ends up in an integer, and "-1" for an unsigned
// seed never reach the program.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace lever::program {

inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

// An interval of reals, and what its values are called in a message ("a fraction", "a duration in seconds").
struct Bounds {
  double lo = 0.0;
  double hi = kUnbounded;
  bool lo_open = false;
  bool hi_open = false;
  std::string_view what = "a number";
};

// The shortest text that reads back as `v` ("0.1", "86400", "1e+300"): never 309 digits.
std::string short_number(double v);
// "a fraction in [0, 1)", "a number >= 0", "a duration in seconds in (0, 86400]".
std::string describe(const Bounds& b);
// nullopt when v is finite and in bounds; otherwise "must be <describe(b)>, got <v>".
std::optional<std::string> check_number(double v, const Bounds& b);
// The same for text as typed: it must be a whole decimal number (strtod's syntax, no hex, no trailing bytes).
std::optional<std::string> check_number_text(std::string_view text, const Bounds& b);
// Whole numbers: decimal digits only (no sign below 0, no fraction, no exponent) in [lo, hi].
std::optional<std::string> check_whole_text(std::string_view text, std::uint64_t lo, std::uint64_t hi,
                                            std::string_view what = "a whole number");

// CLI11 validators built on the checks above; the option's name is put in front of the message by parse().
CLI::Validator number(Bounds b);
CLI::Validator whole(std::uint64_t lo, std::uint64_t hi, std::string_view what = "a whole number");
// A seed: any whole number a std::uint64_t holds, refused rather than wrapped outside it.
CLI::Validator seed();

// Shared ranges with physical meaning, so every program states them alike.
// A Weber fraction: the smallest perceivable relative change; at 1 a fall to zero would never be perceived.
inline constexpr Bounds kWeberFraction{0.0, 1.0, false, true, "a fraction"};
// A prefilter cut-off at the 1 kHz control rate: 0 switches it off, Nyquist (500 Hz) and above aliases.
inline constexpr Bounds kCutoffAt1kHz{0.0, 500.0, false, true, "a cut-off in Hz below Nyquist (500 Hz at 1 kHz)"};

}  // namespace lever::program
