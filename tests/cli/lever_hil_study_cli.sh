#!/usr/bin/env bash
# lever-hil study as a user runs it: a short 3IFC session on the HIL's simulated pair (intervals of 2 s), then
# lever-study report's Fig. 8 of that session's own intervals: every answered trial's intervals counted, each
# confirmed from the levers' own settings frames, the deadband intervals' traffic below the plain ones'; the same
# seed, the same log bytes; bad input refused (docs/study.md, "Sessions on the HIL's pair").
# usage: lever_hil_study_cli.sh path/to/lever-hil path/to/lever-study
set -uo pipefail
hil=$1 study=$2
source "$(dirname "$0")/lib.sh"

expect_bad() {  # expect_bad NAME EXPECTED_STDERR_SUBSTRING ARGS...
  local name=$1 expected=$2; shift 2
  "$hil" study "$@" >"$work/stdout" 2>"$work/stderr"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: one line on stderr ($(head -c 200 "$work/stderr"))" test "$(wc -l <"$work/stderr")" -eq 1
  check "$name: message mentions '$expected' ($(head -c 200 "$work/stderr"))" grep -qF -- "$expected" "$work/stderr"
  check "$name: nothing on stdout" test ! -s "$work/stdout"
}

"$hil" --help >"$work/help"
check "lever-hil --help lists study" grep -q "^  study " "$work/help"
"$hil" study --help >"$work/study-help"; code=$?
check "study --help: exit 0 (got $code)" test "$code" -eq 0
for option in --log --interval-s --seed --topology --gauge-chain --threshold; do
  check "study --help lists $option" grep -qe "$option" "$work/study-help"
done

# The short session: every answer right (threshold far below p, no lapses) and one right answer ending a pass, so
# each pass takes two trials at its start: passes 1 and 2 at p = 15 %, pass 3 at half of that.
short=(--interval-s 2 --gap-s 0.5 --start-p 0.15 --right-in-a-row 2 --threshold 0.02 --lapse 0)
"$hil" study --log "$work/s.jsonl" --subject hil01 --seed 3 "${short[@]}" >"$work/out" 2>"$work/err"; code=$?
check "study: exit 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
check "study: says SIMULATED and names the HIL's setup ($(cat "$work/out"))" \
  grep -q "SIMULATED session of hil01 (3ifc) on the HIL's pair (one-controller, dad141 gauge, seed 3)" "$work/out"

# The log: the header names the simulated pair and its clock; every interval of every answered trial has bus times,
# frame counts, and both levers' confirmations showing the interval's p (read from their settings frames).
check "the log: header, intervals, confirmations" python3 - "$work/s.jsonl" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
h = lines[0]
assert h["simulated"] is True, h
sim = h["simulator"]
assert sim["topology"] == "one-controller" and sim["gauge_chain"] == "dad141" and sim["seed"] == 3, sim
assert "HIL's clock" in sim["clock"], sim
assert h["config"]["interval_s"] == 2, h["config"]
trials = [r for r in lines[1:] if r["kind"] == "3ifc"]
assert len(trials) == 6, len(trials)
for r in trials:
    assert r["void"] is None and r["answer"] == r["carrier"], r
    for i in r["intervals"]:
        # The bus's clock is its newest frame's time (as the kernel's receive times): an interval ends at the first
        # frame 2 s or more after its start, and the longest the bus is silent is a heartbeat period (25 ms, each
        # lever sends one whatever its deadband holds back).
        length = i["end_bus_us"] - i["start_bus_us"]
        assert 2_000_000 <= length <= 2_025_000, length
        assert i["frames_velocity"] > 0 and i["frames_force"] > 0, i
        c = i["confirmed"]
        assert abs(c["hsi"]["p"] - i["p_velocity"]) < 1e-4 and abs(c["top"]["p"] - i["p_force"]) < 1e-4, i
        assert c["hsi"]["at_bus_us"] <= i["start_bus_us"] and c["top"]["at_bus_us"] <= i["start_bus_us"], i
PY

# Fig. 8 of the session's own intervals: 6 trials of 3 intervals, each counted once a direction.
"$study" report "$work/s.jsonl" --table traffic --format csv >"$work/traffic.csv"; code=$?
check "report --table traffic --format csv: exit 0 (got $code)" test "$code" -eq 0
check "report: the 18 intervals counted in each direction, each point simulated" python3 - "$work/traffic.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for d in ("velocity", "force"):
    n = sum(int(r["n"]) for r in rows if r["direction"] == d)
    assert n == 18, (d, n, rows)
assert all(r["simulated"] == "true" for r in rows), rows
PY
# The deadband sends a sample only when it differs from the last one sent by more than p of it, so for one signal
# it sends at most what p = 0 sends (every change), plus its refreshes; it sends fewer by every change that stays
# within p (docs/study.md, "Sessions on the HIL's pair"). Force (the gauge's noise and slow presses within 10 %):
# the carrying intervals at p >= 10 % below the plain ones by more than three of the plain intervals' standard
# deviations. Velocity (one encoder count a tick, 0.38 rad/s, exceeds 10 % of the operator's speeds): no reduction
# to see in 2 s intervals, so only not above the plain ones by more than that spread.
traffic_check() {  # traffic_check DIRECTION below|not-above
  python3 - "$work/traffic.csv" "$1" "$2" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
d, rule = sys.argv[2], sys.argv[3]
plain = [r for r in rows if r["direction"] == d and float(r["p"]) == 0.0]
high = [r for r in rows if r["direction"] == d and float(r["p"]) >= 0.10]
assert len(plain) == 1 and high, rows
n = sum(int(r["n"]) for r in high)
mean_high = sum(int(r["n"]) * float(r["mean_percent"]) for r in high) / n
mean_plain, spread = float(plain[0]["mean_percent"]), 3 * float(plain[0]["sd_percent"])
ok = mean_high < mean_plain - spread if rule == "below" else mean_high <= mean_plain + spread
print(f"{d}: p >= 10 % {mean_high:.2f} % over {n} intervals, p = 0 {mean_plain:.2f} % +- {spread:.2f}", file=sys.stderr)
sys.exit(0 if ok else 1)
PY
}
check "report: force traffic at p >= 10 % below the plain intervals' ($(tr '\n' ' ' <"$work/traffic.csv"))" \
  traffic_check force below
check "report: velocity traffic at p >= 10 % not above the plain intervals'" traffic_check velocity not-above
"$study" report "$work/s.jsonl" >"$work/report"
check "report: the session is labelled simulated, on the simulated pair" \
  grep -q "run on a simulated pair (lever-hil study: topology one-controller, gauge chain dad141, seed 3)" \
  "$work/report"

cp "$work/s.jsonl" "$work/s.before"
"$study" simulate-session --log "$work/s.jsonl" --resume >/dev/null 2>"$work/err"; code=$?
check "simulate-session --resume of a HIL session: refused, exit 2 (got $code: $(cat "$work/err"))" test "$code" -eq 2
check "simulate-session --resume of a HIL session: says why, the log untouched" \
  sh -c 'grep -q "run lever-hil study again" "$1" && cmp -s "$2" "$3"' - "$work/err" "$work/s.jsonl" "$work/s.before"

# The same seed, the same bytes; another seed, another session.
# Answers that vary (a threshold among the staircase's p), so the observer's draws count as much as the HIL's.
tiny=(--interval-s 0.5 --gap-s 0 --right-in-a-row 1 --threshold 0.15)
"$hil" study --log "$work/a.jsonl" --seed 5 "${tiny[@]}" >/dev/null 2>&1
"$hil" study --log "$work/b.jsonl" --seed 5 "${tiny[@]}" >/dev/null 2>&1
"$hil" study --log "$work/c.jsonl" --seed 6 "${tiny[@]}" >/dev/null 2>&1
check "the same seed: the same log, byte for byte" cmp -s "$work/a.jsonl" "$work/b.jsonl"
check "another seed: another log" test -s "$work/c.jsonl" -a -n "$(cmp "$work/a.jsonl" "$work/c.jsonl" 2>&1)"

# A session stopped by SIGTERM (10-minute intervals: far from done half a second in) ends by the signal and leaves
# neither its log nor the temporary beside it. (SIGINT: a script's background job ignores it.)
mkdir "$work/k"
"$hil" study --log "$work/k/k.jsonl" --interval-s 600 >/dev/null 2>&1 &
pid=$!
sleep 0.5
kill -TERM "$pid"
wait "$pid"; code=$?
check "SIGTERM: ends by the signal, exit 143 (got $code)" test "$code" -eq 143
check "SIGTERM: no log and no temporary left ($(ls -A "$work/k"))" test -z "$(ls -A "$work/k")"

expect_bad "an existing log" "exists: a session log is never written over" --log "$work/s.jsonl"
check "an existing log: left as it was" cmp -s "$work/s.jsonl" "$work/s.before"
expect_bad "--interval-s 0" "--interval-s must be" --log "$work/x.jsonl" --interval-s 0
expect_bad "--interval-s nan" "--interval-s must be" --log "$work/x.jsonl" --interval-s nan
expect_bad "--topology" "--topology must be one of" --log "$work/x.jsonl" --topology mesh
expect_bad "--seed -1" "--seed must be a seed" --log "$work/x.jsonl" --seed -1
expect_bad "--protocol" "--protocol" --log "$work/x.jsonl" --protocol staircase
expect_bad "--start-p above --max-p" "start_p" --log "$work/x.jsonl" --start-p 0.3 --max-p 0.25
expect_bad "a staircase option with --protocol rating" "--start-p belongs to --protocol 3ifc" \
  --log "$work/x.jsonl" --protocol rating --start-p 0.1
expect_bad "--gauge-chain" "--gauge-chain must be one of" --log "$work/x.jsonl" --gauge-chain ad620
expect_bad "the force loop on the paper's chain" "makes the contact chatter on the assumed AD620 chain" \
  --log "$work/x.jsonl" --gauge-chain paper-adc --hsi-force-loop on
expect_bad "--log -" "--log must name a file" --log -
expect_bad "--log in a missing directory" "does not exist" --log "$work/no/such/x.jsonl"
check "bad input: no log left behind" test ! -e "$work/x.jsonl"
report "lever-hil study"
