# Project-wide target conventions, applied per target (no global flags).

# C++20, strict warnings as errors, and the sanitizers when LEVER_SANITIZE is on.
function(lever_target_defaults target)
  # Private on purpose: a header-only library must not push -Werror onto third-party code its users compile.
  set(scope PRIVATE)
  target_compile_features(${target} ${scope} cxx_std_20)
  target_compile_options(${target} ${scope} -Wall -Wextra -Werror -Wshadow -Wconversion -Wno-sign-conversion)
  # The same arithmetic on every architecture: GCC fuses a*b+c into one FMA instruction where the machine has one
  # (arm64, not x86-64's baseline), which rounds once instead of twice. The HIL's seeded runs, and the codec's
  # sender and receiver models on two different boards, must compute the same bits (lever/math/elementary.hpp).
  target_compile_options(${target} ${scope} -ffp-contract=off)
  # GCC 12 reports a false -Wrestrict inside libstdc++'s std::string operator+ at -O3 (GCC bug 105651, fixed
  # in 13); every string concatenation would otherwise need a workaround.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} ${scope} -Wno-restrict)
  endif()
  if(LEVER_SANITIZE)
    target_compile_options(${target} ${scope} -fsanitize=address,undefined -fno-omit-frame-pointer
                                              -fno-sanitize-recover=all)
    target_link_options(${target} ${scope} -fsanitize=address,undefined)
  endif()
endfunction()

# A unit test program (Catch2): its test cases in ctest, labelled unit, with exit 77 (skip.hpp) reported as a skip.
# With LEVER_UNIT_TESTS off the program is neither built by default nor in ctest: scripts/test's Release tree, whose
# unit tests run in its ASan+UBSan tree and, in Release, on arm64 (docs/deploy.md, "CI's schedule").
function(lever_unit_tests target prefix)
  if(LEVER_UNIT_TESTS)
    catch_discover_tests(${target} TEST_PREFIX "${prefix}" PROPERTIES LABELS unit SKIP_RETURN_CODE 77)
  else()
    set_target_properties(${target} PROPERTIES EXCLUDE_FROM_ALL ON)
  endif()
endfunction()
