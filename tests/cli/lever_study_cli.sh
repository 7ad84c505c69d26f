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
# Fig. 8 from a log as a runner writes one: the simulated session's records given bus times, frame counts and the
# levers' confirmations (velocity 60 % - 2 p, force 30 % - p of the 1 kHz samples, each interval 20 s on the bus).
# Planted among them, each with frame counts that would move every figure: an interval no lever confirmed, one the
# TOP confirmed at another p, and a familiarization step, all to be left out.
python3 - "$work/whole.jsonl" "$work/bus.jsonl" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
lines[0]["simulated"] = False
t = 0
planted = 0
for r in lines[1:]:
    for i in r["intervals"]:
        t += 21_000_000
        i["start_bus_us"], i["end_bus_us"] = t, t + 20_000_000
        i["frames_velocity"] = round(20_000 * (0.6 - 2 * i["p_velocity"]))
        i["frames_force"] = round(20_000 * (0.3 - i["p_force"]))
        i["confirmed"] = {"hsi": {"mode": "deadband", "p": i["p_velocity"]},
                          "top": {"mode": "deadband", "p": i["p_force"]}}
        if r["kind"] == "familiarization":
            i["frames_velocity"] = i["frames_force"] = 19_999
        elif r["kind"] == "3ifc" and planted < 2 and i["p_velocity"] == 0:
            i["frames_velocity"] = i["frames_force"] = 19_999
            if planted == 0:
                i["confirmed"] = None
            else:
                i["confirmed"]["top"]["p"] = 0.1
            planted += 1
with open(sys.argv[2], "w") as out:
    for r in lines:
        out.write(json.dumps(r) + "\n")
PY
"$study" report --format csv --table traffic "$work/bus.jsonl" >"$work/traffic.csv"; code=$?
check "report --table traffic: exit 0 (got $code)" test "$code" -eq 0
check "report --table traffic: its header by name" \
  test "$(head -1 "$work/traffic.csv")" = "direction,p,simulated,n,mean_percent,sd_percent,min_percent,max_percent"
check "report --table traffic: the velocity's plain intervals at 60 %, none of the planted ones among them" \
  grep -qE '^velocity,0,false,[0-9]+,60,0,60,60$' "$work/traffic.csv"
check "report --table traffic: the force's plain intervals at 30 %" grep -qE '^force,0,false,[0-9]+,30,0,30,30$' \
  "$work/traffic.csv"
check "report --table traffic: each p of the session, per direction, at 60 % - 2 p and 30 % - p" \
  python3 -c '
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1])))
ps = {round(i["p_velocity"], 6) for l in open(sys.argv[2]) for r in [json.loads(l)] if r.get("kind") == "3ifc"
      for i in r["intervals"]}
assert {round(float(r["p"]), 6) for r in rows if r["direction"] == "velocity"} == ps, ps
for r in rows:
    want = 100 * (0.6 - 2 * float(r["p"])) if r["direction"] == "velocity" else 100 * (0.3 - float(r["p"]))
    assert abs(float(r["mean_percent"]) - want) < 0.01, r' "$work/traffic.csv" "$work/whole.jsonl"
"$study" report --table traffic "$work/bus.jsonl" >"$work/traffic.txt"; code=$?
check "report --table traffic in text: exit 0 (got $code)" test "$code" -eq 0
check "report --table traffic in text: the Fig. 8 table" grep -q "^traffic against p (Fig. 8)" "$work/traffic.txt"
check "report --table traffic in text: that table alone" bash -c "! grep -qE 'Fig. (7|11)' '$work/traffic.txt'"
check "report --table traffic in text: the planted intervals counted as left out" \
  grep -qE "left out: 0 of void trials, 2 not confirmed by both levers, 0 without" "$work/traffic.txt"
check "report --table traffic in text: not labelled simulated" bash -c "! grep -qi simulated '$work/traffic.txt'"
check "report --table traffic in text: the velocity's plain intervals" \
  grep -qE '^velocity +0\.00% +[0-9]+ +60\.00% +0\.00% +60\.00% +60\.00%$' "$work/traffic.txt"
"$study" report "$work/whole.jsonl" >"$work/simtraffic.txt"
check "report of a simulated session: no traffic, and why" \
  grep -q "none: .*a simulated session has none" "$work/simtraffic.txt"

# --plots: the three figures as PNGs, the tables beside them, the titles saying which sessions were simulated.
png() { test -s "$1" && test "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a; }
"$study" report "$work/bus.jsonl" "$work/rating.jsonl" --plots "$work/plots/new" >"$work/plots.out" 2>"$work/plots.err"
code=$?
check "report --plots: exit 0 (got $code; $(head -c 200 "$work/plots.err"))" test "$code" -eq 0
for f in fig7 fig8 fig11; do check "report --plots: $f.png is a PNG, not empty" png "$work/plots/new/$f.png"; done
check "report --plots: the tables beside them, as --format csv prints them" \
  cmp -s "$work/plots/new/traffic.csv" "$work/traffic.csv"
check "report --plots: where the plots are" grep -q "^plots: .*fig7.png .*fig8.png .*fig11.png" "$work/plots.out"
check "report --plots: some sessions simulated, said in the titles" grep -q "(some sessions SIMULATED)" \
  "$work/plots/new/plots.gp"
rm "$work/plots/new/fig8.png"
check "report --plots: plots.gp redraws them from another directory" \
  bash -c "cd / && gnuplot '$work/plots/new/plots.gp' 2>/dev/null && test -s '$work/plots/new/fig8.png'"
"$study" report "$work/whole.jsonl" --plots "$work/plots/sim" >/dev/null 2>&1; code=$?
check "report --plots of simulated sessions only: exit 0 (got $code)" test "$code" -eq 0
check "report --plots of simulated sessions only: titled SIMULATED" \
  grep -q 'set title "SIMULATED sessions, not data: ' "$work/plots/sim/plots.gp"
check "report --plots of simulated sessions only: Fig. 7, no Fig. 8 without frame counts" \
  eval "png '$work/plots/sim/fig7.png' && test ! -e '$work/plots/sim/fig8.png'"
"$study" report --format csv "$work/whole.jsonl" --plots "$work/plots/csv" >"$work/plots.csv" 2>/dev/null
check "report --format csv --plots: stdout holds the CSV alone" \
  cmp -s "$work/plots.csv" <("$study" report --format csv "$work/whole.jsonl")
touch "$work/afile"
expect_bad "report --plots onto a file" "afile exists and is not a directory" \
  report "$work/whole.jsonl" --plots "$work/afile"
mkdir -p "$work/plots/taken/fig7.png"
expect_bad "report --plots with a directory where a PNG goes" "fig7.png" report "$work/whole.jsonl" --plots \
  "$work/plots/taken"
"$study" report "$work/whole.jsonl" --plots /proc/lever-study-plots >"$work/stdout" 2>"$work/stderr"; code=$?
check "report --plots where no directory can be made: exit 1 (got $code)" test "$code" -eq 1
check "report --plots where no directory can be made: says so ($(head -c 200 "$work/stderr"))" \
  grep -q "cannot create /proc/lever-study-plots" "$work/stderr"
env PATH=/nonexistent "$study" report "$work/whole.jsonl" --plots "$work/plots/nognuplot" >/dev/null 2>"$work/stderr"
code=$?
check "report --plots without gnuplot: exit 1 (got $code)" test "$code" -eq 1
check "report --plots without gnuplot: says so ($(head -c 200 "$work/stderr"))" \
  grep -q "gnuplot could not be started; the CSV files and plots.gp are in" "$work/stderr"
check "report --plots without gnuplot: the CSV files are left" test -s "$work/plots/nognuplot/thresholds.csv"
expect_bad "simulate-session over an existing log" "cannot be created" simulate-session --log "$work/whole.jsonl"
expect_bad "simulate-session --protocol other" "--protocol" simulate-session --log "$work/x.jsonl" --protocol other

expect_bad "no subcommand" "subcommand"
expect_bad "report --table other" "--table must be one of thresholds, traffic, or ratings" report --table other \
  "$work/whole.jsonl"
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
