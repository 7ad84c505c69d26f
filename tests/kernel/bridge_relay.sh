#!/usr/bin/env bash
# Runs inside the kernel rig (tools/kernel-rig/run-in-guest): two lever-bridges join vcan0 and vcan1 over UDP on
# loopback. can-utils are the independent peers: cangen and cansend produce, candump records, canplayer replays.
# usage: bridge_relay.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
frames() { sed -E 's/^\([0-9.]+\) [a-z0-9]+ //' "$1"; }  # "ID#DATA" per line, time and interface stripped
same() { [[ -s $1 ]] && diff "$1" "$2"; }                  # equal and not empty: two empty files prove nothing

"$bin/lever-bridge" --can vcan0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key" --site-id 1 \
  --record "$out/bridge-a.log" --stats-json >"$out/a.stats" 2>"$out/a.err" &
bridge_a=$!
"$bin/lever-bridge" --can vcan1 --bind 127.0.0.1:5001 --peer 127.0.0.1:5000 --key "$key" --site-id 2 \
  --stats-json >"$out/b.stats" 2>"$out/b.err" &
bridge_b=$!
candump -r 8388608 -L vcan0 >"$out/vcan0.log" &
dump0=$!
candump -r 8388608 -L vcan1 >"$out/vcan1.log" &
dump1=$!
check "both bridges and both candumps are up" wait_until_true 60 all_waiting $bridge_a $bridge_b $dump0 $dump1

# Real time by default (root may): the two relay threads under SCHED_FIFO 40, housekeeping under the normal policy.
policy_of() {  # policy_of PID THREAD_NAME: "FIFO 40", "OTHER 0", ...; empty when no thread has the name
  local task
  for task in /proc/"$1"/task/*; do
    [[ $(cat "$task/comm") == "$2" ]] || continue
    chrt -p "${task##*/}" | awk -F': ' '/policy/ { sub(/^SCHED_/, "", $2); p = $2 } /priority/ { print p, $2 }'
  done
}
check "relay thread lever-can-rx runs under SCHED_FIFO 40" test "$(policy_of $bridge_a lever-can-rx)" = "FIFO 40"
check "relay thread lever-net-rx runs under SCHED_FIFO 40" test "$(policy_of $bridge_a lever-net-rx)" = "FIFO 40"
check "housekeeping (the main thread) stays under the normal policy" \
  test "$(chrt -p $bridge_a | awk -F': ' '/policy/ { sub(/^SCHED_/, "", $2); print $2 }')" = OTHER
check "no real-time warning where it is allowed" test -z "$(grep -F 'real-time scheduling refused' "$out/a.err")"

# vcan0 -> vcan1: 1000 motion frames with counting payloads at 1 kHz, interleaved with ids the default
# allow-list must stop (0x160: the first id past the lever protocol's settings frames); then vcan1 -> vcan0: 500
# force frames.
cangen vcan0 -I 101 -L 8 -D i -g 1 -n 1000 &
gen=$!
for id in 160 200 7FF 000 5A5; do cansend vcan0 "$id#DEADBEEF"; sleep 0.05; done
wait $gen
cangen vcan1 -I 111 -L 8 -D i -g 1 -n 500
# Until the last frame of each direction has crossed (or 60 s: a failure's bound), then the bridges stop.
crossed() { logged "$out/vcan1.log" 101 1000 && logged "$out/vcan0.log" 111 500; }
wait_until_true 60 crossed
kill -TERM $bridge_a $bridge_b
wait $bridge_a; code_a=$?
wait $bridge_b; code_b=$?
kill $dump0 $dump1; wait $dump0 $dump1 2>/dev/null

check "bridge A exits 0 on SIGTERM" test "$code_a" -eq 0
check "bridge B exits 0 on SIGTERM" test "$code_b" -eq 0
frames "$out/vcan0.log" | grep -E '^(101|111)#' >"$work/lever-on-0"
frames "$out/vcan1.log" | grep -E '^(101|111)#' >"$work/lever-on-1"
# (Files, not <(...): the guest's /dev has no /dev/fd.)
for side in 0 1; do for id in 101 111; do grep "^$id#" "$work/lever-on-$side" >"$work/$id-on-$side"; done; done
check "1000 motion frames crossed vcan0 -> vcan1, in order, unchanged" same "$work/101-on-0" "$work/101-on-1"
check "500 force frames crossed vcan1 -> vcan0, in order, unchanged" same "$work/111-on-1" "$work/111-on-0"
check "all 1000 generated" test "$(grep -c '^101#' "$work/lever-on-0")" -eq 1000
check "all 500 generated" test "$(grep -c '^111#' "$work/lever-on-1")" -eq 500
check "disallowed ids did not cross" test -z "$(frames "$out/vcan1.log" | grep -E '^(160|200|7FF|000|5A5)#')"
check "bridge A counted the 5 disallowed frames" test "$(tail -1 "$out/a.stats" | jq .to_network.disallowed)" -eq 5
check "no authentication failures, gaps or drops" \
  test "$(tail -1 "$out/b.stats" | jq '.from_network | .auth_failures + .sequence_gaps + .duplicates + .can_down_drops')" -eq 0
check "stats report one-way latency" test "$(tail -1 "$out/b.stats" | jq '.round_trip_us != null')" = true

# The recording: every frame bridge A saw on vcan0 and wrote onto it, both directions, candump -L format.
check "recording holds both directions" \
  test "$(frames "$out/bridge-a.log" | grep -cE '^(101|111)#')" -eq 1500
check "recording is in candump -L format" \
  test -z "$(grep -vE '^\([0-9]+\.[0-9]{6}\) vcan0 [0-9A-F]{3}#([0-9A-F]{2}){0,8}$' "$out/bridge-a.log")"
check "log2asc converts the recording" log2asc -I "$out/bridge-a.log" -O "$work/rec.asc" vcan0
# Replayed onto vcan1 with canplayer, candump sees the same frames in the same order.
candump -r 8388608 -L vcan1 >"$out/replay.log" &
dump=$!
check "the replay's candump is up" wait_until_true 60 waiting $dump
canplayer -I "$out/bridge-a.log" vcan1=vcan0
has_lines() { (($(wc -l <"$1") >= $2)); }  # has_lines FILE N
wait_until_true 60 has_lines "$out/replay.log" "$(wc -l <"$out/bridge-a.log")"
kill $dump; wait $dump 2>/dev/null
frames "$out/bridge-a.log" >"$work/recorded"
frames "$out/replay.log" >"$work/replayed"
check "canplayer replays the recording frame for frame" same "$work/recorded" "$work/replayed"

# Where real time is refused (an unprivileged user without LimitRTPRIO: EPERM), one warning and the frames still
# cross.
shared=$(mktemp -d)
chmod 755 "$shared"
install -o 65534 -g 65534 -m 600 "$key" "$shared/site.key"
unprivileged() { exec setpriv --reuid 65534 --regid 65534 --clear-groups --inh-caps=-all "$@"; }
unprivileged "$bin/lever-bridge" --can vcan0 --bind 127.0.0.1:5010 --peer 127.0.0.1:5011 --key "$shared/site.key" \
  --site-id 1 >/dev/null 2>"$out/c.err" &
bridge_c=$!
unprivileged "$bin/lever-bridge" --can vcan1 --bind 127.0.0.1:5011 --peer 127.0.0.1:5010 --key "$shared/site.key" \
  --site-id 2 >/dev/null 2>"$out/d.err" &
bridge_d=$!
candump -r 8388608 -L vcan1 >"$out/unprivileged.log" &
dump=$!
check "unprivileged: both bridges and the candump are up" wait_until_true 60 all_waiting $bridge_c $bridge_d $dump
cangen vcan0 -I 102 -L 8 -D i -g 2 -n 20
wait_until_true 60 logged "$out/unprivileged.log" 102 20
kill -TERM $bridge_c $bridge_d
wait $bridge_c; code_c=$?
wait $bridge_d
kill $dump; wait $dump 2>/dev/null
check "unprivileged: one warning that real time was refused" \
  test "$(grep -c 'WARNING: real-time scheduling refused' "$out/c.err")" -eq 1
check "unprivileged: the frames still cross" test "$(grep -c ' 102#' "$out/unprivileged.log")" -eq 20
check "unprivileged: it exits 0 on SIGTERM (exited $code_c)" test "$code_c" -eq 0

finish "bridge relay"
