#pragma once
// The terminal, through ncurses: puts the screen's lines up and reads the keys. Nothing else of lever-view sees
// ncurses (its macros stay in curses_screen.cpp).
#include <cstddef>
#include <cstdio>
#include <vector>

#include "screen_text.hpp"

namespace lever::view {

class CursesScreen {
 public:
  static constexpr int kNoKey = -1;
  static constexpr int kResize = -2;

  // Output to stdout; keys from stdin, or from /dev/tty when stdin is not a terminal (it may be a status input).
  CursesScreen();
  ~CursesScreen();
  CursesScreen(const CursesScreen&) = delete;
  CursesScreen& operator=(const CursesScreen&) = delete;

  void draw(const std::vector<Line>& lines);
  // A key pressed within timeout_ms, kResize when the terminal changed size, or kNoKey.
  int key(int timeout_ms);
  std::size_t columns() const;

 private:
  std::FILE* keys_ = nullptr;  // /dev/tty when opened for the keys
  void* screen_ = nullptr;     // ncurses' SCREEN
  bool colours_ = false;
};

}  // namespace lever::view
