#!/usr/bin/env bash
# The freestanding checker must fail on an object that uses the heap, and on one it cannot read.
# usage: check_rejects.sh CHECKER OBJECT
if "$1" "$2" 2>/dev/null; then
  echo "freestanding check accepted $2, which calls operator new or does not exist" >&2
  exit 1
fi
echo "freestanding check rejects $2, as it should"
