#!/usr/bin/env bash
# lever-view as a user runs it, on a machine without CAN: --help and --version, and each bad input refused with
# exit 2 and one line naming it before any socket is opened. The bus itself: tests/kernel/lever_view.sh.
# usage: lever_view_cli.sh path/to/lever-view
set -uo pipefail
view=$1
source "$(dirname "$0")/lib.sh"

# expect_bad NAME EXPECTED_STDERR_SUBSTRING ARGS...: exit 2, one stderr line, nothing on stdout
expect_bad() {
  local name=$1 expected=$2; shift 2
  "$view" "$@" >"$work/stdout" 2>"$work/stderr" </dev/null
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: one line on stderr ($(head -c 300 "$work/stderr"))" test "$(wc -l <"$work/stderr")" -eq 1
  check "$name: message mentions '$expected'" grep -qF -- "$expected" "$work/stderr"
  check "$name: nothing on stdout" test ! -s "$work/stdout"
}

"$view" --help >"$work/help"
check "--help exits 0 and names the keys and the exit codes" grep -q "q quit" "$work/help"
check "--help: exit codes" grep -q "^Exit codes: 0 success" "$work/help"
check "--version" test "$("$view" --version)" = "lever-view $(sed -n 's/^project(lever_testbed VERSION \([0-9.]*\).*/\1/p' "$(dirname "$0")/../../CMakeLists.txt")"

expect_bad "no interface" "--can" --json
expect_bad "an interface name the kernel refuses" "contains '/'" --can a/b --json
expect_bad "an interface name too long" "--can" --can abcdefghijklmnop --json
expect_bad "a pair out of range" "--pair" --can vcan0 --pair 16 --json
expect_bad "a bit rate out of range" "--bitrate" --can vcan0 --bitrate 5 --json
expect_bad "a refresh rate of 0" "--refresh-hz" --can vcan0 --refresh-hz 0 --json
expect_bad "a NaN duration" "--duration" --can vcan0 --duration nan --json
expect_bad "an unknown option" "--colour" --can vcan0 --colour --json
expect_bad "a status file that is not there" "$work/none.stats" --can vcan0 --status "$work/none.stats" --json
expect_bad "a status directory" "is a directory" --can vcan0 --status "$work" --json
expect_bad "stdin twice" "stdin can be given once" --can vcan0 --status - --status - --json
expect_bad "no terminal for the screen" "not a terminal" --can vcan0
report lever-view
