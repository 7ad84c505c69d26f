#pragma once
// lever-view's screen as lines of text, from a snapshot: the ncurses layer only puts them on the terminal, so what
// the screen says is tested without a terminal.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pair_monitor.hpp"

namespace lever::view {

// How a line is drawn: the terminal colours these if it can.
enum class Tone : std::uint8_t { normal, heading, good, warning, bad };

struct Line {
  std::string text;
  Tone tone = Tone::normal;
};

// What the reader knows that the monitor does not.
struct ReaderState {
  std::string interface;
  bool link_up = true;
  std::uint64_t kernel_drops = 0;  // frames the kernel dropped for a full receive queue: this view's own loss
};

struct ScreenOptions {
  std::size_t width = 120;
  bool utf8 = true;  // the sparklines in block elements; otherwise in ASCII
  bool frozen = false;
  double bitrate = 1e6;
  std::optional<double> pictures_per_s;  // how often the screen is drawn, as measured
};

std::vector<Line> render(const Snapshot& snapshot, const ReaderState& reader, const ScreenOptions& options);

// The sparkline of the newest `width` samples, scaled between their own minimum and maximum; a sample with no
// value is a blank.
std::string sparkline(const std::vector<std::optional<float>>& samples, std::size_t width, bool utf8);

// At most `columns` characters of UTF-8 text (each taken as one column wide, as the screen's are).
std::string clip_columns(const std::string& text, std::size_t columns);

}  // namespace lever::view
