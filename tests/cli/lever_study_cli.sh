#!/usr/bin/env bash
# lever-study as a user runs it: help, version, a small simulation labelled simulated, a report of a log it wrote
# itself, and bad input (exit 2, one line, nothing on stdout).
# usage: lever_study_cli.sh path/to/lever-study
set -uo pipefail
study=$1
source "$(dirname "$0")/lib.sh"

expect_bad() {  # expect_bad NAME EXPECTED_STDERR_SUBSTRING ARGS...
  local name=$1 expected=$2; shift 2
  "$study" "$@" >"$work/stdout" 2>"$work/stderr"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: one line on stderr ($(head -c 200 "$work/stderr"))" test "$(wc -l <"$work/stderr")" -eq 1
  check "$name: message mentions '$expected' ($(head -c 200 "$work/stderr"))" grep -qF -- "$expected" "$work/stderr"
  check "$name: nothing on stdout" test ! -s "$work/stdout"
}

"$study" --help >"$work/help"; code=$?
check "--help: exit 0 (got $code)" test "$code" -eq 0
for verb in simulate report; do check "--help lists $verb" grep -q "^  $verb " "$work/help"; done
check "--help ends with the exit status" grep -q "^Exit status: 0 done" "$work/help"
check "--version: lever-study and a version" grep -qE '^lever-study [0-9]+\.[0-9]+' <("$study" --version)

"$study" simulate --sessions 50 --thresholds 0.1 >"$work/text"; code=$?
check "simulate: exit 0 (got $code)" test "$code" -eq 0
check "simulate: labelled simulated" grep -q "^SIMULATED" "$work/text"
"$study" simulate --sessions 50 --thresholds 0.1,0.2 --format json >"$work/json"
check "simulate --format json: simulated true, two thresholds" \
  python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); assert j["simulated"] is True and len(j["results"]) == 2' \
  "$work/json"
"$study" simulate --sessions 50 --thresholds 0.1 --format csv >"$work/csv"
check "simulate --format csv: a header and four rows, each simulated" \
  test "$(grep -c '^true,0.1,' "$work/csv")" -eq 4 -a "$(head -1 "$work/csv" | cut -d, -f1)" = simulated
check "simulate: the same seed, the same output" \
  cmp -s "$work/csv" <("$study" simulate --sessions 50 --thresholds 0.1 --format csv)

# A log written by hand the way the library writes one: header, familiarization, a void trial.
cat >"$work/s01.jsonl" <<'LOG'
{"record":"session","format":1,"protocol":"3ifc","subject":"s01","seed":1,"simulated":true,"config":{}}
{"record":"trial","attempt":1,"kind":"familiarization","pass":0,"trial":0,"p":0.0,"direction":"both","carrier":null,"answer":null,"right":null,"void":null,"intervals":[{"p_velocity":0.0,"p_force":0.0,"duration_s":0.0}]}
{"record":"trial","attempt":2,"kind":"3if
LOG
"$study" report "$work/s01.jsonl" >"$work/report" 2>"$work/report.err"; code=$?
check "report of a log cut mid-line: exit 0 (got $code)" test "$code" -eq 0
check "report: the cut line is a warning" grep -q "warning: .*line 3" "$work/report.err"
check "report: the simulated session is labelled" grep -q "SIMULATED" "$work/report"

# A simulated session written whole, then the same cut by a "kill" mid-line and resumed: every complete record
# before the cut is kept as it was, the session ends, and report reads both.
"$study" simulate-session --log "$work/whole.jsonl" --subject sim01 --seed 4 >/dev/null; code=$?
check "simulate-session: exit 0 (got $code)" test "$code" -eq 0
check "simulate-session: the header says simulated" grep -q '"simulated":true' <(head -1 "$work/whole.jsonl")
cp "$work/whole.jsonl" "$work/cut.jsonl"
keep=$(head -n 12 "$work/whole.jsonl" | wc -c)
truncate -s $((keep + 30)) "$work/cut.jsonl"
"$study" simulate-session --log "$work/cut.jsonl" --resume --seed 4 >/dev/null 2>"$work/resume.err"; code=$?
check "simulate-session --resume of a cut log: exit 0 (got $code)" test "$code" -eq 0
check "--resume: the cut line is a warning" grep -q "warning: .*line 13" "$work/resume.err"
check "--resume: the twelve complete lines are kept byte for byte" \
  cmp -s <(head -n 12 "$work/whole.jsonl") <(head -n 12 "$work/cut.jsonl")
check "--resume: no cut line left in the log" \
  python3 -c 'import json,sys; [json.loads(l) for l in open(sys.argv[1])]' "$work/cut.jsonl"
"$study" simulate-session --protocol rating --log "$work/rating.jsonl" --subject sim02 >/dev/null
"$study" report "$work/whole.jsonl" "$work/cut.jsonl" "$work/rating.jsonl" >"$work/report2"; code=$?
check "report of three simulated logs: exit 0 (got $code)" test "$code" -eq 0
check "report: two subjects' thresholds" test "$(grep -c '^sim01 \*' "$work/report2")" -eq 2
check "report: ratings of both directions" test "$(grep -cE '^(velocity|force) ' "$work/report2")" -eq 24
"$study" report --format csv --table ratings "$work/rating.jsonl" >"$work/ratings.csv"
check "report --table ratings: a header and 24 rows" test "$(wc -l <"$work/ratings.csv")" -eq 25
expect_bad "simulate-session over an existing log" "cannot be created" simulate-session --log "$work/whole.jsonl"
expect_bad "simulate-session --protocol other" "--protocol" simulate-session --log "$work/x.jsonl" --protocol other

expect_bad "no subcommand" "subcommand"
expect_bad "misspelt subcommand" "unknown subcommand 'simulat'" simulat
expect_bad "--sessions 0" "--sessions must be a whole number in [1, 10000000], got 0" simulate --sessions 0
expect_bad "--thresholds 0" "--thresholds must be a fraction in (0, 1)" simulate --thresholds 0.1,0
expect_bad "--thresholds nan" "--thresholds must be" simulate --thresholds nan
expect_bad "--lapse 0.5" "--lapse must be a rate in [0, 0.5)" simulate --lapse 0.5
expect_bad "--slope -1" "--slope must be" simulate --slope -1
expect_bad "--format xml" "must be one of text, json, or csv" simulate --format xml
expect_bad "--seed -1" "--seed" simulate --seed -1
expect_bad "start above the cap" "start_p must be a fraction in (0, max_p]" simulate --start-p 0.3
expect_bad "report without a log" "logs is required" report
expect_bad "report of a missing log" "cannot be read" report "$work/none.jsonl"
printf 'not json\n{}\n' >"$work/bad.jsonl"
expect_bad "report of a damaged log" "line 1 is not JSON" report "$work/bad.jsonl"
printf '%s\n' '{"record":"session","format":1,"protocol":"3ifc","subject":"s","seed":1,"config":{"step":-1}}' \
  >"$work/badconfig.jsonl"
expect_bad "report of a log with a bad config" "step must be" report "$work/badconfig.jsonl"
# run: what is refused before any bus is opened, and a bus that is not there (exit 1, the log not created).
expect_bad "run without --can" "--can is required" run --log "$work/run.jsonl" --subject s
expect_bad "run: a new session without a subject" "needs --subject" run --can vcan0 --log "$work/run.jsonl"
expect_bad "run: a simulated session's log" "a simulated session" run --can vcan0 --log "$work/whole.jsonl"
expect_bad "run: a damaged log" "line 1 is not JSON" run --can vcan0 --log "$work/bad.jsonl"
expect_bad "run --pair 16" "--pair" run --can vcan0 --pair 16 --log "$work/run.jsonl" --subject s
"$study" run --can nosuchcan0 --log "$work/run.jsonl" --subject s >"$work/stdout" 2>"$work/stderr" </dev/null
code=$?
check "run on an interface that is not there: exit 1 (got $code)" test "$code" -eq 1
check "run on an interface that is not there: says so ($(head -c 200 "$work/stderr"))" grep -q "nosuchcan0" "$work/stderr"
check "run on an interface that is not there: no log written" test ! -e "$work/run.jsonl"
check "--help lists run" grep -q "^  run " "$work/help"
report "lever-study cli"
