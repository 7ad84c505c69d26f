# Shared by the CLI tests: a scratch directory removed on exit, and check NAME COMMAND... counting results.
# Source it after setting `set -uo pipefail`; end the test with `report PROGRAM`.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0 failed=0
check() {
  local name=$1; shift
  if "$@"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAILED: $name" >&2; fi
}
report() {
  echo "$1: $passed passed, $failed failed"
  test "$failed" -eq 0
}
