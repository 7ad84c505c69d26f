#!/usr/bin/env bash
# scripts/check-skips on made-up ctest JUnit files: a skip on the allowed list passes with its reason printed; a
# skip not on it, or one that printed no reason, fails the run; tests that ran are not its business.
# usage: check_skips.sh path/to/scripts/check-skips
set -uo pipefail
check_skips=$1
source "$(dirname "$0")/lib.sh"

junit() {  # STATUS OUTPUT: one test case "t: x" with that status and output
  printf '<?xml version="1.0" encoding="UTF-8"?>\n<testsuite tests="2">\n'
  printf '<testcase name="t: ran" status="run"><system-out>ok</system-out></testcase>\n'
  printf '<testcase name="t: x" status="%s"><skipped message="SKIP_RETURN_CODE=77"/><system-out>%s</system-out></testcase>\n' "$1" "$2"
  printf '</testsuite>\n'
}
printf '# comment\nt: x | the machine has no such thing\n' >"$work/allowed.txt"
: >"$work/none.txt"

junit notrun $'some output\nSKIPPED: no /dev/full here' >"$work/skip.xml"
"$check_skips" "$work/skip.xml" "$work/allowed.txt" >"$work/out"; code=$?
check "an allowed skip: exit 0 (got $code)" test "$code" -eq 0
check "an allowed skip: its name, reason and why it is allowed are printed" \
  grep -qF "skipped (allowed: the machine has no such thing): t: x: no /dev/full here" "$work/out"

"$check_skips" "$work/skip.xml" "$work/none.txt" >"$work/out"; code=$?
check "a skip not on the list: exit 1 (got $code)" test "$code" -eq 1
check "a skip not on the list: named with its reason" grep -qF "SKIPPED, not allowed: t: x: no /dev/full here" "$work/out"

junit notrun $'cross-build: cannot install\n  arm64 is not built' >"$work/exit77.xml"
"$check_skips" "$work/exit77.xml" "$work/none.txt" >"$work/out"; code=$?
check "a script's exit 77: its last line is the reason (got $(cat "$work/out"))" grep -qF "t: x: arm64 is not built" "$work/out"

junit notrun "" >"$work/silent.xml"
"$check_skips" "$work/silent.xml" "$work/allowed.txt" >"$work/out"; code=$?
check "a skip without a reason fails even when listed: exit 1 (got $code)" test "$code" -eq 1

junit run "SKIPPED: printed, but the test ran" >"$work/ran.xml"
"$check_skips" "$work/ran.xml" "$work/none.txt" >"$work/out"; code=$?
check "tests that ran are not skips: exit 0 (got $code)" test "$code" -eq 0

printf 't: x without a reason\n' >"$work/bad-list.txt"
"$check_skips" "$work/skip.xml" "$work/bad-list.txt" >/dev/null 2>"$work/err"; code=$?
check "a malformed list: exit 2 (got $code)" test "$code" -eq 2
"$check_skips" "$work/missing.xml" "$work/allowed.txt" >/dev/null 2>&1; code=$?
check "a missing JUnit file: exit 2 (got $code)" test "$code" -eq 2

report "check-skips"
