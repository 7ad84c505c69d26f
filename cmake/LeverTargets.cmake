# Project-wide target conventions, applied per target (no global flags).

# C++20, strict warnings as errors, and the sanitizers when LEVER_SANITIZE is on.
function(lever_target_defaults target)
  # Private on purpose: a header-only library must not push -Werror onto third-party code its users compile.
  set(scope PRIVATE)
  target_compile_features(${target} ${scope} cxx_std_20)
  target_compile_options(${target} ${scope} -Wall -Wextra -Werror -Wshadow -Wconversion -Wno-sign-conversion)
  if(LEVER_SANITIZE)
    target_compile_options(${target} ${scope} -fsanitize=address,undefined -fno-omit-frame-pointer
                                              -fno-sanitize-recover=all)
    target_link_options(${target} ${scope} -fsanitize=address,undefined)
  endif()
endfunction()
