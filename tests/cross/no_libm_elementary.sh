#!/usr/bin/env bash
# The simulation takes its transcendental functions from lever::math, never from libm, whose last bits differ between
# machines (the same seed would then mean another run on another architecture): fails when an object in the given
# archives or objects needs one of libm's.
# usage: no_libm_elementary.sh ARCHIVE_OR_OBJECT...
set -euo pipefail
(($# > 0)) || { echo "usage: $0 ARCHIVE_OR_OBJECT..." >&2; exit 2; }
libm='^(a?sinh?|a?cosh?|a?tanh?|atan2|sincos|exp|exp2|exp10|expm1|log|log2|log10|log1p|pow|hypot|cbrt|erfc?|[lt]gamma)[fl]?$'
status=0
for file in "$@"; do
  symbols=$(nm --undefined-only --format=just-symbols "$file") || { echo "$file: cannot read" >&2; exit 2; }
  found=$(grep -E "$libm" <<<"$symbols" | sort -u | tr '\n' ' ' || true)
  if [[ -n $found ]]; then
    echo "$file needs libm's $found; use lever/math/elementary.hpp" >&2
    status=1
  fi
done
((status)) || echo "no libm transcendental function in $*"
exit $status
