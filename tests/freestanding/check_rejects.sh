#!/usr/bin/env bash
# The freestanding checker must fail on an object that uses the heap.
# usage: check_rejects.sh CHECKER OBJECT
if "$1" "$2" 2>/dev/null; then
  echo "freestanding check accepted $2, which calls operator new" >&2
  exit 1
fi
echo "freestanding check rejects a heap-using object, as it should"
