#include "curses_screen.hpp"

#include <unistd.h>

#include <stdexcept>
#include <string>

// ncurses last: its macros (erase, clear, move, timeout) would rewrite the standard library's names.
#include <curses.h>

namespace lever::view {
namespace {

enum ColourPair : short { kGood = 1, kWarning = 2, kBad = 3 };

}  // namespace

CursesScreen::CursesScreen() {
  if (!isatty(STDIN_FILENO)) {
    keys_ = std::fopen("/dev/tty", "r");
    if (keys_ == nullptr) throw std::runtime_error("no terminal to read keys from (/dev/tty)");
  }
  SCREEN* screen = newterm(nullptr, stdout, keys_ != nullptr ? keys_ : stdin);
  if (screen == nullptr) throw std::runtime_error("ncurses cannot drive this terminal (TERM?)");
  screen_ = screen;
  set_term(screen);
  cbreak();
  noecho();
  keypad(stdscr, TRUE);
  curs_set(0);
  if (has_colors()) {
    start_color();
    use_default_colors();
    init_pair(kGood, COLOR_GREEN, -1);
    init_pair(kWarning, COLOR_YELLOW, -1);
    init_pair(kBad, COLOR_RED, -1);
    colours_ = true;
  }
}

CursesScreen::~CursesScreen() {
  endwin();
  delscreen(static_cast<SCREEN*>(screen_));
  if (keys_ != nullptr) std::fclose(keys_);
}

std::size_t CursesScreen::columns() const { return COLS > 0 ? static_cast<std::size_t>(COLS) : 80; }

void CursesScreen::draw(const std::vector<Line>& lines) {
  werase(stdscr);
  const auto width = columns();
  for (std::size_t i = 0; i < lines.size() && i < static_cast<std::size_t>(LINES); ++i) {
    attr_t attributes = A_NORMAL;
    switch (lines[i].tone) {
      case Tone::heading:
        attributes = A_BOLD;
        break;
      case Tone::good:
        attributes = colours_ ? COLOR_PAIR(kGood) : A_NORMAL;
        break;
      case Tone::warning:
        attributes = colours_ ? COLOR_PAIR(kWarning) : A_NORMAL;
        break;
      case Tone::bad:
        attributes = colours_ ? COLOR_PAIR(kBad) | A_BOLD : A_BOLD;
        break;
      case Tone::normal:
        break;
    }
    attron(attributes);
    // One column short of the edge: a character in the last column of the last line would scroll the screen.
    mvaddstr(static_cast<int>(i), 0, clip_columns(lines[i].text, width - 1).c_str());
    attroff(attributes);
  }
  wrefresh(stdscr);
}

int CursesScreen::key(int timeout_ms) {
  wtimeout(stdscr, timeout_ms);
  const int k = wgetch(stdscr);
  if (k == KEY_RESIZE) return kResize;
  return k == ERR ? kNoKey : k;
}

}  // namespace lever::view
