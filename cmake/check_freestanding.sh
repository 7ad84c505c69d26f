#!/usr/bin/env bash
# usage: check_freestanding.sh OBJECT...
# Fails when an object file needs any symbol outside the freestanding allow-list: heap (operator new,
# malloc), exceptions (__cxa_*, _Unwind_*), RTTI or any OS call would show up here as an undefined symbol.
set -euo pipefail
allowed='^(sqrtf?|expf?|logf?|sinf?|cosf?|fabsf?|memcpy|memmove|memset|memcmp)$'
status=0
for object in "$@"; do
  while read -r symbol; do
    if [[ ! $symbol =~ $allowed ]]; then
      echo "$object: needs '$(c++filt "$symbol")', which freestanding code must not use" >&2
      status=1
    fi
  done < <(nm --undefined-only --format=just-symbols "$object")
done
[[ $status -eq 0 ]] && echo "freestanding: $# object(s) need only: $allowed"
exit $status
