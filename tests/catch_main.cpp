// The tests' main(), compiled here rather than taken from Debian's libCatch2WithMain.a: that archive is built for
// the build machine only (the catch2 package is amd64, Multi-Arch: foreign), so a cross build could not link it.
// Catch2 2.13 is header-only otherwise, so this one file is all a cross build needs. Catch2 2 has no skip of its
// own: a run with a LEVER_SKIP (skip.hpp) and no failure exits 77, ctest's skip code.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>
#include <cstdio>

#include "skip.hpp"

namespace {
bool g_skipped = false;
}  // namespace

void lever::test::note_skip(const std::string& why) {
  std::printf("SKIPPED: %s\n", why.c_str());
  std::fflush(stdout);
  g_skipped = true;
}

int main(int argc, char** argv) {
  const int failed = Catch::Session().run(argc, argv);
  return failed == 0 && g_skipped ? 77 : failed;
}
