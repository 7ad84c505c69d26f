// The tests' main(), compiled here rather than taken from Debian's libCatch2WithMain.a: that archive is built for
// the build machine only (the catch2 package is amd64, Multi-Arch: foreign), so a cross build could not link it.
// Catch2 2.13 is header-only otherwise, so this one file is all a cross build needs.
#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>
