#!/usr/bin/env bash
# lever-ctl as a user runs it, where no CAN interface is needed: help, version, and bad input (exit 2, one line,
# nothing on stdout). Its work on a bus is tests/kernel/lever_ctl.sh's and the pair tests'.
# usage: lever_ctl_cli.sh path/to/lever-ctl
set -uo pipefail
ctl=$1
source "$(dirname "$0")/lib.sh"

expect_bad() {  # expect_bad NAME EXPECTED_STDERR_SUBSTRING ARGS...
  local name=$1 expected=$2; shift 2
  "$ctl" "$@" >"$work/stdout" 2>"$work/stderr"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: one line on stderr ($(head -c 200 "$work/stderr"))" test "$(wc -l <"$work/stderr")" -eq 1
  check "$name: message mentions '$expected' ($(head -c 200 "$work/stderr"))" grep -qF -- "$expected" "$work/stderr"
  check "$name: nothing on stdout" test ! -s "$work/stdout"
}

"$ctl" --help >"$work/help"; code=$?
check "--help: exit 0 (got $code)" test "$code" -eq 0
for verb in arm disarm rearm home tare set-deadband; do
  check "--help lists $verb" grep -q "^  $verb " "$work/help"
  "$ctl" "$verb" --help >"$work/sub" 2>&1; code=$?
  check "$verb --help: exit 0 (got $code), --pair and --can" test "$code" -eq 0 -a "$(grep -c -- '--pair\|--can' "$work/sub")" -ge 2
done
check "--help ends with the exit status" grep -q "^Exit status: 0 done" "$work/help"
check "--version: lever-ctl and a version" grep -qE '^lever-ctl [0-9]+\.[0-9]+' <("$ctl" --version)

expect_bad "no subcommand" "subcommand" --pair 0 --can vcan0
expect_bad "misspelt subcommand" "unknown subcommand 'amr'" amr --pair 0 --can vcan0
expect_bad "no --can" "--can is required" arm --pair 0
expect_bad "no --pair" "--pair is required" arm --can vcan0
expect_bad "--pair 16" "--pair must be a whole number in [0, 15], got 16" arm --pair 16 --can vcan0
expect_bad "--pair -1" "--pair must be a whole number in [0, 15]" arm --pair -1 --can vcan0
expect_bad "--timeout 0" "--timeout must be a duration in seconds in (0, 3600]" arm --pair 0 --can vcan0 --timeout 0
expect_bad "--timeout nan" "--timeout must be" arm --pair 0 --can vcan0 --timeout nan
expect_bad "an interface name no interface can have" "--can 'a/b'" arm --pair 0 --can a/b
expect_bad "an empty interface name" "--can ''" arm --pair 0 --can ''
expect_bad "set-deadband without --direction" "--direction is required" set-deadband --pair 0 --can vcan0 --p 0.1
expect_bad "set-deadband --direction sideways" "must be one of motion or force" \
  set-deadband --pair 0 --can vcan0 --direction sideways --p 0.1
expect_bad "set-deadband --p 1" "--p must be a fraction in [0, 1)" set-deadband --pair 0 --can vcan0 --direction force --p 1
expect_bad "set-deadband --floor 70" "--floor must be" set-deadband --pair 0 --can vcan0 --direction force --p 0.1 --floor 70
expect_bad "an option of another subcommand" "--p" arm --pair 0 --can vcan0 --p 0.1
report "lever-ctl cli"
