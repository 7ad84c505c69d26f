#!/usr/bin/env bash
# Runs inside the kernel rig: an attacker on the path between two lever-bridges records what A sends B, B restarts,
# and the recording is replayed at the new B. Nothing of it may reach B's bus: the restarted B has an empty replay
# window, and only the epoch its datagrams carry (docs/datagram-format.md, "Restarts") tells the recording apart.
# Genuine traffic after the restart still flows. Last, B refuses datagrams from a site other than its configured peer.
#   A (vcan0, :5000) -> proxy (:5100 | :5101) -> B (vcan1, :5001)
# usage: bridge_restart_replay.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"

start_b() {  # start_b N: B's Nth run
  "$bin/lever-bridge" --can vcan1 --bind 127.0.0.1:5001 --peer 127.0.0.1:5101 --key "$key" --site-id 2 \
    --peer-site-id 1 --stats-json >"$out/b$1.stats" 2>"$out/b$1.err" &
  bridge_b=$!
}
proxy() {  # proxy SECONDS [--capture FILE]
  "$bin/lever-bridge-attack" --kind proxy --from 127.0.0.1:5101 --to 127.0.0.1:5001 --listen 127.0.0.1:5100 \
    --back 127.0.0.1:5000 --duration "$@" >>"$out/proxy.txt" &
  proxy_pid=$!
}
"$bin/lever-bridge" --can vcan0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5100 --key "$key" --site-id 1 \
  --peer-site-id 2 --stats-json >"$out/a.stats" 2>"$out/a.err" &
bridge_a=$!
start_b 1
candump -r 8388608 -L vcan1 >"$out/vcan1.log" &
dump=$!
proxy 4 --capture "$work/capture.bin"
sleep 1.5  # the bridges' first exchange, through the proxy

# 1. Recorded: 50 frames, id 0x101, counting payloads.
cangen vcan0 -I 101 -L 8 -D i -g 5 -n 50
wait $proxy_pid
count() { grep -c " $1#" "$out/vcan1.log"; }
check "before the restart all 50 frames crossed" test "$(count 101)" -eq 50
captured=$(grep -o '[0-9]* captured' "$out/proxy.txt" | cut -d' ' -f1)
check "the proxy recorded A's datagrams (got ${captured:-0})" test "${captured:-0}" -ge 50

# 2. B restarts; the recording is replayed at it from its peer's address, twice.
kill -HUP $bridge_b; wait $bridge_b; code_b1=$?  # a closed terminal or session: the same clean stop as SIGTERM
check "B's first run exits 0 on SIGHUP (got $code_b1)" test "$code_b1" -eq 0
start_b 2
sleep 1
"$bin/lever-bridge-attack" --kind replay-capture --from 127.0.0.1:5101 --to 127.0.0.1:5001 \
  --capture "$work/capture.bin" >>"$out/attacks.txt"
"$bin/lever-bridge-attack" --kind replay-capture --from 127.0.0.1:5101 --to 127.0.0.1:5001 \
  --capture "$work/capture.bin" >>"$out/attacks.txt"
sleep 0.5
check "the replayed recording put no frame on B's bus" test "$(count 101)" -eq 50

# 3. Genuine traffic after the restart: the proxy relays again (and records nothing), 20 frames of id 0x102.
proxy 5
sleep 2.5  # A and B learn each other's new epochs through the proxy (probes every second)
cangen vcan0 -I 102 -L 8 -D i -g 5 -n 20
sleep 0.5
check "after the restart genuine frames flow (20 sent)" test "$(count 102)" -eq 20
wait $proxy_pid

# 4. --peer-site-id: datagrams with the key, from the peer's address, echoing B's epoch, but from site 9.
# (Sequence numbers a day ahead of the wall clock, past A's; the probe that learns B's epoch is from site 1.)
"$bin/lever-bridge-attack" --key "$key" --from 127.0.0.1:5101 --to 127.0.0.1:5001 --kind valid --count 10 \
  --sender 9 --probe-sender 1 --sequence $(( $(date +%s) * 1000000 + 86400000000 )) >>"$out/attacks.txt"
sleep 0.3
check "another site's datagrams put nothing on B's bus" test "$(count 101)" -eq 50
kill -TERM $bridge_a $bridge_b
wait $bridge_b; code_b=$?
wait $bridge_a
kill $dump; wait $dump 2>/dev/null

stat() { tail -1 "$out/b2.stats" | jq ".from_network.$1"; }
check "the restarted B exits 0" test "$code_b" -eq 0
check "the first replay counted as stale (got $(stat stale))" test "$(stat stale)" -ge "$captured"
check "the second as duplicates (got $(stat duplicates))" test "$(stat duplicates)" -ge "$captured"
check "another site's datagrams counted (got $(stat wrong_site))" test "$(stat wrong_site)" -eq 10
check "nothing else reached B's bus" test "$(grep -cv ' 10[12]#' "$out/vcan1.log")" -eq 0

finish "bridge restart replay"
