#!/usr/bin/env bash
# End-to-end checks of the lever-codec program as a user runs it: exit codes, messages, files left behind.
# usage: lever_codec_cli.sh path/to/lever-codec
set -uo pipefail
codec=$1
source "$(dirname "$0")/lib.sh"

# expect_bad NAME EXPECTED_STDERR_SUBSTRING ARGS...: exit 2, one stderr line, no output file left.
expect_bad() {
  local name=$1 expected=$2; shift 2
  rm -f "$work/out.csv"
  "$codec" "$@" >"$work/stdout" 2>"$work/stderr"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: one line on stderr" test "$(wc -l <"$work/stderr")" -eq 1
  check "$name: message mentions '$expected'" grep -qF -- "$expected" "$work/stderr"
  check "$name: nothing on stdout" test ! -s "$work/stdout"
  check "$name: no output file" test ! -e "$work/out.csv"
  check "$name: no temporary left" test -z "$(find "$work" -name '.out.csv.*')"
}

printf 't,x\n0,1\n0.001,1.05\n0.002,1.2\n0.003,1.21\n' >"$work/good.csv"
printf 't,x\n0,1\n0.001,oops\n' >"$work/nonnumeric.csv"
printf 't,x\n0,1\n0.001,nan\n' >"$work/nan.csv"
printf 't,x\n0,1\n0.001,inf\n' >"$work/inf.csv"
printf 't,x\n0,1\n0,2\n' >"$work/time.csv"
printf 't,x\n0,1,3\n' >"$work/columns.csv"
printf 'time,value\n0,1\n' >"$work/header.csv"

expect_bad "missing file" "$work/none.csv: cannot open" --p 0.1 --in "$work/none.csv" --out "$work/out.csv"
expect_bad "non-numeric" "nonnumeric.csv:3: 'oops' in column 'x' is not a number" --in "$work/nonnumeric.csv" --out "$work/out.csv"
expect_bad "nan" "nan.csv:3: 'nan'" --in "$work/nan.csv" --out "$work/out.csv"
expect_bad "inf" "inf.csv:3: 'inf'" --in "$work/inf.csv" --out "$work/out.csv"
expect_bad "time" "time.csv:3: time 0 does not increase" --in "$work/time.csv" --out "$work/out.csv"
expect_bad "columns" "columns.csv:2: expected 2 columns, found 3" --in "$work/columns.csv" --out "$work/out.csv"
expect_bad "header" "header.csv:1: bad header" --in "$work/header.csv" --out "$work/out.csv"
expect_bad "negative p" "--p" --p -0.1 --in "$work/good.csv" --out "$work/out.csv"
expect_bad "zero cut-off" "--filter-hz" --filter-hz 0 --in "$work/good.csv" --out "$work/out.csv"
expect_bad "negative cut-off" "--filter-hz" --filter-hz -3 --in "$work/good.csv" --out "$work/out.csv"
expect_bad "unknown mode" "--mode" --mode zigzag --in "$work/good.csv" --out "$work/out.csv"
expect_bad "no input" "--in and --out are required" --p 0.1
expect_bad "unwritable output" "the directory $work/no/such/dir does not exist" --in "$work/good.csv" --out "$work/no/such/dir/out.csv"

"$codec" --help >"$work/help" 2>&1
check "--help exits 0" test $? -eq 0
check "--help names the modes" grep -q "predictive" "$work/help"

"$codec" --mode deadband --p 0.1 --in "$work/good.csv" --out "$work/out.csv" >"$work/summary.json"
check "good run exits 0" test $? -eq 0
check "summary is one JSON object with the promised fields" \
  jq -e '.samples == 4 and .sent == 2 and .rate == 0.5 and (.rmse | type == "number") and (.max_error | type == "number")' "$work/summary.json"
check "output header and rows (%.17g)" diff <(printf 't,sent,x_hat\n0,1,1\n0.001,0,1\n0.002,1,1.2\n0.0030000000000000001,0,1.2\n') "$work/out.csv"

"$codec" generate --kind force3 --seed 5 --duration 0.5 --out "$work/f3.csv" >/dev/null
check "generate writes a 3-DoF trace" test "$(head -1 "$work/f3.csv")" = "t,x,y,z"
"$codec" --mode predictive --p 0.05 --filter-hz 30 --in "$work/f3.csv" --out "$work/f3-out.csv" >"$work/f3.json"
check "3-DoF output header" test "$(head -1 "$work/f3-out.csv")" = "t,sent,x_hat,y_hat,z_hat"
check "3-DoF output has one row per sample" test "$(wc -l <"$work/f3-out.csv")" -eq 501

report "lever-codec cli"
