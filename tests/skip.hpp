#pragma once
// A test case that this machine cannot run says so, and why: LEVER_SKIP("no /dev/full here") prints
// "SKIPPED: <why>" and returns from the test case. The tests' main() (catch_main.cpp) then exits 77 if nothing
// failed, which ctest reports as skipped (SKIP_RETURN_CODE), and scripts/check-skips fails the run on any skip not
// on tests/allowed_skips.txt. Only in a TEST_CASE's own body, before what it is about is checked.
#include <string>

namespace lever::test {

void note_skip(const std::string& why);

}  // namespace lever::test

#define LEVER_SKIP(why)            \
  do {                             \
    ::lever::test::note_skip(why); \
    return;                        \
  } while (false)
