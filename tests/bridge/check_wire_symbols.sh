#!/usr/bin/env bash
# usage: check_wire_symbols.sh OBJECT...
# The datagram codec must not reach the heap, exceptions, RTTI or the OS: every undefined symbol of its object
# (compiled with -fno-exceptions -fno-rtti, host/bridge/CMakeLists.txt) must be libsodium's HMAC or a memory
# routine. ctest also runs it on the whole library, where it must fail (key.cpp throws and allocates).
# Exit status: 0 clean, 1 a symbol outside the list, 2 an object that cannot be read.
set -euo pipefail
allowed='^(memcpy|memmove|memset|memcmp|sodium_init|crypto_auth_hmacsha512256|crypto_auth_hmacsha512256_verify|crypto_auth_hmacsha512256_update|crypto_auth_hmacsha512256_final|crypto_verify_32)$'
status=0
[[ $# -gt 0 ]] || { echo "usage: $0 OBJECT..." >&2; exit 2; }
for object in "$@"; do
  # Read first, so that a missing or unreadable object fails the check instead of passing it.
  symbols=$(nm --undefined-only --format=just-symbols "$object") || { echo "$object: cannot read" >&2; exit 2; }
  while read -r symbol; do
    [[ -n $symbol ]] || continue
    if [[ ! $symbol =~ $allowed ]]; then
      echo "$object: needs '$(c++filt "$symbol")', which the wire codec must not use" >&2
      status=1
    fi
  done <<<"$symbols"
done
[[ $status -eq 0 ]] && echo "wire codec: $# object(s) need only: $allowed"
exit $status
