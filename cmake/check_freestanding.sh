#!/usr/bin/env bash
# usage: check_freestanding.sh OBJECT...
# Fails when an object file needs any symbol outside the freestanding allow-list: heap (operator new,
# malloc), exceptions (__cxa_*, _Unwind_*), RTTI or any OS call would show up here as an undefined symbol.
set -euo pipefail
# sqrt and fabs are exact in IEEE arithmetic, the same on every machine; the transcendental functions come from
# lever/math/elementary.hpp, not libm, whose last bits differ between machines.
allowed='^(sqrtf?|fabsf?|memcpy|memmove|memset|memcmp)$'
# Exit status: 0 clean, 1 a symbol outside the list, 2 an object that cannot be read.
status=0
[[ $# -gt 0 ]] || { echo "usage: $0 OBJECT..." >&2; exit 2; }
for object in "$@"; do
  # Read first, so that a missing or unreadable object fails the check instead of passing it (nm's failure
  # inside a process substitution went unnoticed).
  symbols=$(nm --undefined-only --format=just-symbols "$object") || { echo "$object: cannot read" >&2; exit 2; }
  while read -r symbol; do
    [[ -n $symbol ]] || continue
    if [[ ! $symbol =~ $allowed ]]; then
      echo "$object: needs '$(c++filt "$symbol")', which freestanding code must not use" >&2
      status=1
    fi
  done <<<"$symbols"
done
[[ $status -eq 0 ]] && echo "freestanding: $# object(s) need only: $allowed"
exit $status
