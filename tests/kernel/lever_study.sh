#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): a whole short
# 3IFC session run by lever-study run against the real lever-fw pair behind lever-hil serve (one site, the paper's
# wall-tap operator), answered by a scripted subject, killed with SIGKILL in an interval and resumed from its log.
# The subject answers as the prompts come: an Enter for the familiarization and the briefing, and for each trial the
# interval the experimenter's view names (a test's oracle: the subject's own terminal never shows it), wrong on the
# first trial; one wrong key first, which must be asked again. So the session runs: pass 1 wrong at 10 %, right at
# 15 %; the briefing; pass 2 right at 10 % (killed in its second interval, then resumed); pass 3 right at 5 %
# (half of pass 2's). Intervals of 2 s; one right answer ends a pass. Then a rating session on the same pair.
# usage: lever_study.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
trap stop_all EXIT

one_site study --duration 0 --json
up_and_homed
command vcan0 1
require "both arm" wait_for_serve study "both levers armed"

log=$out/session.jsonl
progress=$out/progress.txt
: >"$progress"
study_args=(run --can vcan0 --pair 0 --protocol 3ifc --subject rig --seed 7 --log "$log" --progress "$progress"
  --interval-s 2 --gap-s 0.5 --start-p 0.10 --step 0.05 --max-p 0.25 --right-in-a-row 1)

# in_interval_2_of PASS: the progress view says pass PASS's first trial is in its second interval
in_interval_2_of() {
  awk -v trial="3ifc pass $1 trial 1:" 'index($0, "attempt ") == 1 { current = index($0, trial) > 0 }
    current && index($0, "interval 2 of 3: p") { found = 1 } END { exit !found }' "$progress"
}
# subject SESSION_OUT ANSWERS_FIFO [KILL_IN_PASS]: answers lever-study's prompts (its stdout, SESSION_OUT) into
# the FIFO; with KILL_IN_PASS, kills lever-study with SIGKILL once that pass's first trial is in its second interval.
answered=0
subject() {
  local session_out=$1 fifo=$2 kill_in=${3:-} seen=0 line carrier
  local -a lines=()
  exec 3>"$fifo"
  while ((1)); do
    if [[ -n $kill_in ]] && in_interval_2_of "$kill_in"; then
      kill -KILL "$study_pid"
      exec 3>&-
      return 0
    fi
    mapfile -t lines <"$session_out"
    while ((seen < ${#lines[@]})); do
      line=${lines[seen]}
      seen=$((seen + 1))
      case $line in
        *"Press Enter"*) echo >&3 ;;
        "Which interval"*)
          carrier=$(grep -o 'carried by interval [1-3]' "$progress" | tail -n 1 | grep -o '[1-3]$')
          answered=$((answered + 1))
          if ((answered == 1)); then
            echo x >&3  # a wrong key, asked again
            echo $((carrier % 3 + 1)) >&3
          else
            echo "$carrier" >&3
          fi ;;
      esac
    done
    kill -0 "$study_pid" 2>/dev/null || { exec 3>&-; return 0; }
    sleep 0.1
  done
}

# The session, killed in pass 2's trial's second interval.
mkfifo "$work/answers1"
: >"$out/subject1.txt"
"$bin/lever-study" "${study_args[@]}" <"$work/answers1" >"$out/subject1.txt" 2>"$out/study1.err" &
study_pid=$!
subject "$out/subject1.txt" "$work/answers1" 2
wait "$study_pid"; code=$?
check "lever-study killed with SIGKILL in an interval (exit $code)" test "$code" -eq 137
check "a wrong key was asked again" grep -q "Please answer a number from 1 to 3" "$out/subject1.txt"
check "the subject's prompts never show p or the carrier" bash -c "! grep -qiE '%|carri|p = |0\\.[0-9]' '$out/subject1.txt'"
records_before=$(($(wc -l <"$log") - 1))
check "the log holds the trials answered before the kill: familiarization, pass 1's two, the briefing ($records_before)" \
  test "$records_before" -eq 4
cp "$log" "$work/killed.jsonl"

mkfifo "$work/answers2"
: >"$out/subject2.txt"
"$bin/lever-study" "${study_args[@]}" <"$work/answers2" >"$out/subject2.txt" 2>"$out/study2.err" &
study_pid=$!
subject "$out/subject2.txt" "$work/answers2"
wait "$study_pid"; code=$?
check "lever-study resumed from its log and ended the session (exit $code)" test "$code" -eq 0
cat "$progress"

jqs() { jq -s -r "$1" "$log"; }
check "no answer lost: the log as the kill left it is the resumed log's beginning, byte for byte" \
  cmp -n "$(stat -c %s "$work/killed.jsonl")" "$work/killed.jsonl" "$log"
check "the session: familiarization, pass 1 wrong then right, briefing, passes 2 and 3 right ($(jqs '[.[1:][] | "\(.kind) \(.pass) \(.right)"] | join(", ")'))" \
  test "$(jqs '[.[1:][] | select(.void == null) | "\(.kind) \(.pass) \(.right)"] | join(", ")')" = \
  "familiarization 0 null, 3ifc 1 false, 3ifc 1 true, briefing 0 null, 3ifc 2 true, 3ifc 3 true"
check "the interrupted trial was repeated, and recorded once: pass 2 has one record" \
  test "$(jqs '[.[1:][] | select(.kind == "3ifc" and .pass == 2)] | length')" -eq 1
check "p per trial: 10, 15, 10, 5 % ($(jqs '[.[1:][] | select(.kind == "3ifc") | .p] | join(" ")'))" \
  test "$(jqs '[.[1:][] | select(.kind == "3ifc") | .p * 1000 | round] | join(" ")')" = "100 150 100 50"
check "every interval's settings confirmed by both levers, as the interval meant them" \
  test "$(jqs '[.[1:][] | select(.void == null) | .intervals[] | (.confirmed.hsi.p - .p_velocity | fabs) < 1e-4 and
                (.confirmed.top.p - .p_force | fabs) < 1e-4] | all')" = true
# An interval's length on the bus's clock: lever-study run ends it at the newest frame it has read once that frame
# is past the length, and it reads in steps of 20 ms (its pump), so the length is over by at most the 20 ms plus the
# bus's longest silence: a lever's heartbeat every 25 of its periods, later by the time its loop lost (the status
# lines' worst_lost_in_window_us, over 68 ms windows; the lever with less of it bounds the silence).
lost_us=$(for role in hsi top; do last_stat $role .worst_lost_in_window_us; done | sort -n | head -1)
over_us=$((20000 + 25000 + ${lost_us:-0}))
check "every 3IFC interval lasted its 2 s on the bus's clock, over by at most $over_us us (20 ms reads + 25 ms heartbeat + $lost_us us lost): $(jqs '[.[1:][] | select(.kind == "3ifc") | .intervals[] | (.end_bus_us - .start_bus_us)] | "\(min) to \(max) us"')" \
  test "$(jqs "[.[1:][] | select(.kind == \"3ifc\") | .intervals[] | (.end_bus_us - .start_bus_us - 2e6) | . >= 0 and . <= $over_us] | all")" = true
# The deadband's interval on the bus: at 10 % and above, fewer data frames (both paths) than each plain interval.
jqs '.[1:][] | select(.kind == "3ifc") | "p \(.p): carrier \(.carrier), frames (velocity+force) \([.intervals[] | "\(.frames_velocity)+\(.frames_force)"] | join(" "))"'
check "each trial's deadband interval sent fewer data frames than either plain one (p >= 10 %)" \
  test "$(jqs '[.[1:][] | select(.kind == "3ifc" and .p >= 0.1) | . as $t | [.intervals[] | .frames_velocity + .frames_force] as $n |
                ($n[$t.carrier - 1]) < ([$n[range(3)] | select(. != $n[$t.carrier - 1])] | min)] | all')" = true
check "lever-study report: the subject's threshold is the mean of the three passes, 10 %" \
  bash -c "'$bin/lever-study' report '$log' | grep -E 'rig.*10(\\.0+)? ?%'"
# Fig. 8 from the rig's log: the four answered trials' intervals, the plain ones at p = 0 (two a trial), and at the
# carriers' 10 % and 15 % each direction's traffic below its own at p = 0.
"$bin/lever-study" report --format csv --table traffic "$log" >"$out/traffic.csv"
cat "$out/traffic.csv"
check "lever-study report --table traffic: the 8 plain intervals at p = 0, per direction" \
  test "$(awk -F, '$2 == 0 { n += $4 } END { print n }' "$out/traffic.csv")" = 16
check "lever-study report --table traffic: at 10 % and 15 %, each direction below its traffic at p = 0" \
  awk -F, 'NR > 1 { m[$1 " " ($2 + 0)] = $5 + 0 }
    END { exit !(m["velocity 0.1"] < m["velocity 0"] && m["velocity 0.15"] < m["velocity 0"] &&
                 m["force 0.1"] < m["force 0"] && m["force 0.15"] < m["force 0"]) }' "$out/traffic.csv"

# A rating session (IV-B-3) on the same pair, intervals of 0.5 s: the familiarization, then run 1 on the velocity
# path only and run 2 on the force path only, each the paper's twelve p in a random order, a rating after each
# interval. The rater answers Enter to the familiarization's prompts and, to each rating, 10 - round(p / 5 %) from
# the p the experimenter's view names (the test's oracle: 10 at p = 0 down to 2 at 40 %), so every answer in the
# log can be checked against its interval's p.
rating_log=$out/rating.jsonl
rating_progress=$out/rating-progress.txt
: >"$rating_progress"
rater() {  # rater SESSION_OUT ANSWERS_FIFO
  local session_out=$1 seen=0 line per_mille
  local -a lines=()
  exec 3>"$2"
  while kill -0 "$study_pid" 2>/dev/null; do
    mapfile -t lines <"$session_out"
    while ((seen < ${#lines[@]})); do
      line=${lines[seen]}
      seen=$((seen + 1))
      case $line in
        *"Press Enter"*) echo >&3 ;;
        "How did it feel"*)
          per_mille=$(grep '^attempt ' "$rating_progress" | tail -n 1 | sed -E 's/.*: p ([0-9]+)\.([0-9])[0-9] %.*/\1\2/')
          echo $((10 - (10#$per_mille + 25) / 50)) >&3 ;;
      esac
    done
    sleep 0.1
  done
  exec 3>&-
}
mkfifo "$work/answers3"
: >"$out/rater.txt"
"$bin/lever-study" run --can vcan0 --pair 0 --protocol rating --subject rig --seed 11 --log "$rating_log" \
  --progress "$rating_progress" --interval-s 0.5 <"$work/answers3" >"$out/rater.txt" 2>"$out/rating.err" &
study_pid=$!
rater "$out/rater.txt" "$work/answers3"
wait "$study_pid"; code=$?
check "the rating session ran to its end (exit $code: $(head -c 200 "$out/rating.err"))" test "$code" -eq 0
rjq() { jq -s -r "$1" "$rating_log"; }
ratings='[.[1:][] | select(.kind == "rating" and .void == null)]'
check "the rater's prompts never show p" bash -c "! grep -qiE '%|carri|p = |0\.[0-9]' '$out/rater.txt'"
check "familiarization first, then 24 ratings ($(rjq '[.[1:][] | select(.void == null) | .kind] | group_by(.) | map("\(.[0]) \(length)") | join(", ")'))" \
  test "$(rjq '[.[1:][] | select(.void == null) | .kind] | (.[0] == "familiarization") and (map(select(. == "rating")) | length) == 24')" = true
paper_p='[0, 25, 50, 75, 100, 125, 150, 200, 250, 300, 350, 400]'
for run in 1:velocity 2:force; do
  check "run ${run%%:*}: the ${run#*:} path only, each of the paper's twelve p once ($(rjq "$ratings | map(select(.pass == ${run%%:*}) | .p * 1000 | round) | join(\" \")"))" \
    test "$(rjq "$ratings | map(select(.pass == ${run%%:*})) | (map(.direction) | unique) == [\"${run#*:}\"] and
                  (map(.p * 1000 | round) | sort) == $paper_p")" = true
done
check "the order is random: neither run rates the twelve p in ascending order" \
  test "$(rjq ". as \$all | [1, 2] | map(. as \$r | \$all | $ratings | map(select(.pass == \$r) | .p) | . == sort) | any")" = false
check "every rating interval's settings confirmed by both levers: p on the run's path, 0 on the other" \
  test "$(rjq "$ratings | map(.p as \$p | .direction as \$d | .intervals[0].confirmed as \$c |
                ((\$c.hsi.p - (if \$d == \"velocity\" then \$p else 0 end)) | fabs) < 1e-4 and
                ((\$c.top.p - (if \$d == \"force\" then \$p else 0 end)) | fabs) < 1e-4) | all")" = true
lost_us=$(for role in hsi top; do last_stat $role .worst_lost_in_window_us; done | sort -n | head -1)
over_us=$((20000 + 25000 + ${lost_us:-0}))
check "every rating interval lasted its 0.5 s on the bus's clock, over by at most $over_us us (as the 3IFC ones): $(rjq "$ratings | map(.intervals[0] | .end_bus_us - .start_bus_us) | \"\\(min) to \\(max) us\"")" \
  test "$(rjq "$ratings | map(.intervals[0] | (.end_bus_us - .start_bus_us - 5e5) | . >= 0 and . <= $over_us) | all")" = true
check "no answer lost or misplaced: each logged rating is the rater's answer to its interval's p" \
  test "$(rjq "$ratings | map(.answer == 10 - (((.p * 1000 | round) + 25) / 50 | floor)) | all")" = true
"$bin/lever-study" report --format csv --table ratings "$rating_log" >"$out/ratings.csv"
cat "$out/ratings.csv"
check "lever-study report --table ratings: 24 rows of one rating each, the mean the rater's answer to that p" \
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { n++; pm = int($c["p"] * 1000 + 0.5); want = 10 - int((pm + 25) / 50); if ($c["n"] != 1 || $c["mean"] + 0 != want) bad++ }
    END { exit !(n == 24 && bad == 0) }' "$out/ratings.csv"
finish "a 3IFC session and a rating session by lever-study on the pair"
