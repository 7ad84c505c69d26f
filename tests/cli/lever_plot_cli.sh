#!/usr/bin/env bash
# lever-plot as a user runs it, on a recording lever_one_site made in the kernel rig (tests/cli/one-site-session.tar.xz: its candump -L
# log and both levers' --stats-json lines, xz-compressed): the figures it prints against tools/dbc-decode --summary
# and the levers' own counters, the PNGs, a lever-hil trace, and garbage (one line, exit 2).
# usage: lever_plot_cli.sh path/to/lever-plot path/to/lever-hil REPO_ROOT
set -uo pipefail
plot=$1 hil=$2 root=$3
source "$(dirname "$0")/lib.sh"
run() {  # run ARGS...: never more than 60 s; sets code, output in $work/out and $work/err
  timeout 60 "$plot" "$@" >"$work/out" 2>"$work/err" </dev/null
  code=$?
}
"$plot" --help >"$work/help"; check "--help exits 0" test $? -eq 0
check "--help names the status lines" grep -q -- "--status" "$work/help"
"$plot" --version >"$work/version"; check "--version exits 0" test $? -eq 0

tar -C "$work" -xJf "$root/tests/cli/one-site-session.tar.xz"
log=$work/one-site.candump
run "$log" --status "$work/hsi.stats" --status "$work/top.stats" --out "$work/session"
check "the recording: exit 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
cp "$work/out" "$work/summary"
# Frames per message as lever-plot counts them, and as the DBC alone decodes them.
"$root/tools/dbc-decode" --summary "$root/common/protocol/lever.dbc" "$log" |
  jq -r '.messages | to_entries[] | "\(.key) \(.value.frames)"' | sort >"$work/dbc-counts"
awk '$1 ~ /^Lever/ { print $1, $2 }' "$work/summary" | sort >"$work/plot-counts"
check "five messages counted" test "$(wc -l <"$work/plot-counts")" -eq 5
check "frames per message equal dbc-decode --summary's ($(tr '\n' ' ' <"$work/plot-counts") vs $(tr '\n' ' ' <"$work/dbc-counts"))" \
  cmp -s "$work/plot-counts" "$work/dbc-counts"
# Each lever's own count of the data and refresh frames it sent, at its last status line the log holds.
for role in HSI TOP; do
  line=$(grep "^  $role at its last placed status line" "$work/summary")
  read -r sent refresh logged logged_refresh <<<"$(sed -E 's/.*data_sent ([0-9]+), refresh_sent ([0-9]+); in the log by then: data ([0-9]+), refresh ([0-9]+)/\1 \2 \3 \4/' <<<"$line")"
  check "$role: data_sent $sent is the log's $logged" test "${sent:-x}" = "${logged:-y}"
  check "$role: refresh_sent $refresh is the log's $logged_refresh" test "${refresh:-x}" = "${logged_refresh:-y}"
  check "$role: the pair sent data ($sent frames)" test "${sent:-0}" -gt 100
done
last_hsi=$(tail -1 "$work/hsi.stats" | jq .data_sent)
check "the HSI's last status line: data_sent $last_hsi, the LeverMotion count" grep -qE "^  LeverMotion +$last_hsi " "$work/summary"
check "frames.csv: one row per frame of the pair" \
  test "$(($(wc -l <"$work/session/frames.csv") - 1))" -eq "$(awk '{ n += $2 } END { print n }' "$work/plot-counts")"
check "frames.csv: named columns" grep -q "^t,iface,message,pair,role,position_rad,velocity_rad_s,force_n," "$work/session/frames.csv"
for png in positions force packet_rate states; do
  check "$png.png is a PNG" bash -c "head -c 8 '$work/session/$png.png' | od -An -c | grep -q 'P   N   G'"
done
check "the TOP's positions from its status lines" test "$(awk -F, 'NR > 1 && $3 != ""' "$work/session/timeline.csv" | wc -l)" -ge 20
check "the faults the run ended with" grep -q "faults: .* TOP force_stale" "$work/summary"
check "plots.gp redraws from another directory" bash -c "cd / && gnuplot '$work/session/plots.gp'"

# A plain recording, the tool's most common input: no status lines, so no TOP position. The figures are drawn
# with what the log has, gnuplot says nothing, and one line says what is not drawn.
run "$log" --out "$work/plain"
check "a plain recording: exit 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
check "a plain recording: gnuplot warned of nothing ($(head -c 200 "$work/err"))" test ! -s "$work/err"
for png in positions force packet_rate states; do
  check "a plain recording: $png.png is a PNG" bash -c "head -c 8 '$work/plain/$png.png' | od -An -c | grep -q 'P   N   G'"
done
check "a plain recording: says the TOP's position and the tracking error are not drawn" \
  grep -q "^not drawn: the TOP's position and the tracking error" "$work/out"
check "a plain recording: names the four PNGs" grep -q "^plots: .*positions.png, .*force.png, .*packet_rate.png, .*states.png$" "$work/out"
# Heartbeats alone (a pair that never armed): no data frames, so no positions and no force; the rates and states
# are drawn, and each figure left out is said.
grep -E ' 70[01]#' "$log" >"$work/heartbeats.log"
run "$work/heartbeats.log" --out "$work/heartbeats"
check "heartbeats alone: exit 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
check "heartbeats alone: states.png and packet_rate.png, no positions.png or force.png" \
  bash -c "test -s '$work/heartbeats/states.png' && test -s '$work/heartbeats/packet_rate.png' && test ! -e '$work/heartbeats/positions.png' && test ! -e '$work/heartbeats/force.png'"
check "heartbeats alone: the positions and the force said not drawn" \
  bash -c "grep -q '^not drawn: the HSI.s position' '$work/out' && grep -q '^not drawn: the force' '$work/out'"

# Settings frames (docs/can-protocol.md): counted as dbc-decode counts them, each change listed once, the values in
# frames.csv. The TOP: predictive, changes 42, tares 21, taring, p 0.466, floor 43.981 N, filter 3276.9 Hz; then
# the same frame again (no new line); the HSI's defaults (p 0.1, floor 0.02 rad/s).
t0=$(head -1 "$log" | sed -E 's/^\(([0-9.]+)\).*/\1/')
{ head -50 "$log"
  echo "($t0) vcan0 141#A9553412CDAB0180"; echo "($t0) vcan0 141#A9553412CDAB0180"
  echo "($t0) vcan0 140#0000E80314000000"; tail -n +51 "$log"; } >"$work/settings.log"
run "$work/settings.log" --out "$work/settings" --no-plots
check "a log with settings frames: exit 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
check "the settings frames counted" bash -c "grep -qE '^  LeverSettingsTop +2 ' '$work/out' && grep -qE '^  LeverSettingsHsi +1 ' '$work/out'"
check "each lever's settings listed once per change ($(grep -c 'settings:' "$work/out"))" test "$(grep -c '  settings: ' "$work/out")" -eq 2
check "the TOP's settings as sent" \
  grep -q "settings: .* TOP force: predictive p 0.4660 floor 43.981 N filter 3276.9 Hz (changes 42, tares 21, taring)" "$work/out"
check "the HSI's settings as sent" grep -q "settings: .* HSI motion: deadband p 0.1000 floor 0.020 rad/s filter off (changes 0, tares 0)" "$work/out"
check "frames.csv: every row has the header's columns" \
  test "$(awk -F, '{ print NF }' "$work/settings/frames.csv" | sort -u)" = 27
check "frames.csv: a settings row by named columns" \
  grep -qE '^[0-9.]+,vcan0,LeverSettingsTop,0,top,,,,,,,,,1,,,,,,,,0.4660,43.981,3276.9,42,21,1$' "$work/settings/frames.csv"

# A log with some bad lines: counted in one line, the frames still drawn.
{ head -100 "$log"; echo "garbage"; head -c 3000 /dev/urandom | tr -d '\0'; echo; tail -n +101 "$log"; } >"$work/partly.log"
run "$work/partly.log" --out "$work/partly" --no-plots
check "a log with bad lines: exit 0 (got $code)" test "$code" -eq 0
check "a log with bad lines: says how many were skipped ($(cat "$work/err"))" grep -qE "partly.log: [0-9]+ of [0-9]+ lines skipped" "$work/err"
check "a log with bad lines: one line on stderr" test "$(wc -l <"$work/err")" -eq 1
check "a log with bad lines: the frames still counted" grep -qE "^  LeverMotion +$last_hsi " "$work/out"

# Not a candump -L log at all: one line, exit 2.
head -c 100000 /dev/urandom >"$work/random.bin"
for bad in "$work/random.bin" "$root/common/protocol/lever.dbc"; do
  run "$bad" --out "$work/x" --no-plots
  check "${bad##*/}: exit 2 (got $code)" test "$code" -eq 2
  check "${bad##*/}: not a candump -L log, in one line ($(head -c 200 "$work/err"))" \
    bash -c "test \$(wc -l <'$work/err') -eq 1 && grep -q 'not a candump -L log' '$work/err'"
done
mkdir "$work/adir"
run "$work/adir" --out "$work/x"; check "a directory: exit 2" test "$code" -eq 2
check "a directory: says so" grep -q "a directory, not a candump -L log" "$work/err"
: >"$work/empty.log"
run "$work/empty.log" --out "$work/x"; check "an empty log: exit 2" test "$code" -eq 2
{ head -5 "$log"; echo "(4102444800.000000) vcan0 700#0100000000000000"; } >"$work/jump.log"
run "$work/jump.log" --out "$work/x" --no-plots
check "a clock that jumps by decades: exit 2, at once (got $code)" test "$code" -eq 2
check "a clock that jumps: says so" grep -q "more than a day" "$work/err"
run "$log" --out "$work/x" --pair 16; check "--pair 16: exit 2" test "$code" -eq 2
run "$log" --out "$work/x" --status "$log"; check "a log as status lines: exit 2" test "$code" -eq 2
check "a log as status lines: names the file and line" grep -q "one-site.candump:1: not a lever-fw --stats-json line" "$work/err"

# The HIL's trace: the same command, the same figures.
"$hil" run --scenario wall-tap --duration 3 --seed 1 --p 0.1 --trace "$work/hil.csv" >/dev/null
run "$work/hil.csv" --out "$work/hil"
check "a lever-hil trace: exit 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
motion=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next } { n += $c["motion_sent"] } END { print n }' "$work/hil.csv")
check "a lever-hil trace: its motion frames ($motion) counted" grep -q "motion frames $motion " "$work/out"
check "a lever-hil trace: the positions drawn" test -s "$work/hil/positions.png"
report "lever-plot"
