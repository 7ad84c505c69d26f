#!/usr/bin/env bash
# Every script refuses what it does not take, naming the argument, exit 2, before it does anything (none of these
# calls installs, builds or runs anything).
# usage: scripts_cli.sh REPO_ROOT
set -uo pipefail
root=$1
source "$(dirname "$0")/lib.sh"
refuses() {  # refuses NAME ARGUMENT_NAMED COMMAND...
  local name=$1 named=$2; shift 2
  timeout 20 "$@" >"$work/out" 2>"$work/err" </dev/null
  local code=$?
  check "$name: exit 2 (got $code)" test "$code" -eq 2
  check "$name: names '$named' (got: $(head -c 200 "$work/err"))" grep -qF -- "$named" "$work/err"
  # One line that points to --help, not the whole usage (a new user read past a screen of it to find the cause).
  check "$name: one line on stderr (got $(wc -l <"$work/err"))" test "$(wc -l <"$work/err")" -eq 1
  check "$name: points to --help" grep -qF -- "--help" "$work/err"
}
for script in "$root"/scripts/*; do
  refuses "scripts/${script##*/} --frobnicate" "--frobnicate" "$script" --frobnicate
done
refuses "scripts/package without an architecture" "no architecture" "$root/scripts/package"
refuses "scripts/cross-build without an architecture" "no architecture" "$root/scripts/cross-build"
refuses "scripts/sysroot with two architectures" "got 2 arguments" "$root/scripts/sysroot" arm64 armhf
refuses "scripts/man-pages without its directories" "BIN_DIR and OUT_DIR" "$root/scripts/man-pages"
refuses "scripts/check-skips without a file" "JUNIT_XML" "$root/scripts/check-skips"
refuses "scripts/failed-tests without a file" "JUNIT_XML" "$root/scripts/failed-tests"
refuses "scripts/slowest-tests with a count that is no number" "many" "$root/scripts/slowest-tests" x.xml many
refuses "hil/experiments/gauge-sensitivity --seeds two" "'two'" "$root/hil/experiments/gauge-sensitivity" --seeds two
refuses "scripts/package with an unknown architecture" "'riscv64'" "$root/scripts/package" riscv64
refuses "scripts/package with a fourth argument" "'extra'" "$root/scripts/package" amd64 b d extra
refuses "scripts/cross-build with an unknown architecture" "'riscv64'" "$root/scripts/cross-build" riscv64
refuses "scripts/cross-build with a third argument" "'extra'" "$root/scripts/cross-build" arm64 b extra
refuses "scripts/build-mcu with a second argument" "'extra'" "$root/scripts/build-mcu" dir extra
refuses "scripts/build --target without a name" "--target" "$root/scripts/build" "$work/never-built" --target
refuses "scripts/bench-bridge --frames two" "'two'" "$root/scripts/bench-bridge" --frames two
refuses "scripts/bench-bridge --variants old without --old" "needs --old" "$root/scripts/bench-bridge" --variants old "$root"
refuses "scripts/bench-bridge --variants floor without the floor relay" "no lever-bench-relay-floor" \
  "$root/scripts/bench-bridge" --variants floor "$root"
refuses "scripts/bench-bridge --variants ceiling" "'ceiling'" "$root/scripts/bench-bridge" --variants ceiling "$root"
refuses "hil/experiments/rate-table with a second argument" "'extra'" "$root/hil/experiments/rate-table" dir extra
refuses "hil/experiments/hil-change-bounds-wall-tap with a third argument" "'extra'" "$root/hil/experiments/hil-change-bounds-wall-tap" b 3 extra
refuses "scripts/cpu-budget --shifts 5" "'5'" "$root/scripts/cpu-budget" --shifts 5
refuses "scripts/cpu-budget --frobnicate" "--frobnicate" "$root/scripts/cpu-budget" --frobnicate
refuses "scripts/demo with an argument" "'now'" "$root/scripts/demo" now
refuses "scripts/test with an argument" "'now'" "$root/scripts/test" now
refuses "fuzz/run-datagram-fuzzer --frobnicate" "--frobnicate" "$root/fuzz/run-datagram-fuzzer" --frobnicate
refuses "tools/dbc-decode --frobnicate" "--frobnicate" "$root/tools/dbc-decode" --frobnicate x.dbc
report "scripts"
