#!/usr/bin/env bash
# Runs inside the kernel rig: a lever-bridge survives its CAN interface going down and up, being removed and made
# again, its peer going away and coming back, and a flood; its memory stays bounded.
# usage: bridge_survival.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
start_b() {
  "$bin/lever-bridge" --can vcan1 --bind 127.0.0.1:5001 --peer 127.0.0.1:5000 --key "$key" --site-id 2 \
    >/dev/null 2>>"$out/b.err" &
  bridge_b=$!
}
"$bin/lever-bridge" --can vcan0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key" --site-id 1 \
  --record "$work/a.log" --stats-json >"$out/a.stats" 2>"$out/a.err" &
bridge_a=$!
start_b
candump -r 8388608 -L vcan1 >"$out/vcan1.log" &
dump=$!
check "both bridges and the candump are up" wait_until_true 60 all_waiting $bridge_a $bridge_b $dump
count() { grep -c " $1#" "$out/vcan1.log"; }

# 1. The interface goes down under the bridge and comes back.
cansend vcan0 101#01
sleep 0.2
ip link set vcan0 down
sleep 1
ip link set vcan0 up
sleep 1.5
cansend vcan0 101#02
sleep 0.3
check "frames flow before the interface went down" test "$(grep -c ' 101#01' "$out/vcan1.log")" -eq 1
check "and again after it came back" test "$(grep -c ' 101#02' "$out/vcan1.log")" -eq 1
check "the bridge is still running" kill -0 $bridge_a

# 1b. The interface is removed and made again: the bridge reopens it under the same descriptor number (its CAN
# thread sleeps in recvmmsg on that number), and both directions use the new socket.
ip link del vcan0
sleep 1
ip link add dev vcan0 type vcan
ip link set vcan0 up
sleep 1.5
candump -L vcan0 >"$out/vcan0-remade.log" &
dump0=$!
sleep 0.3
cansend vcan0 101#04
cansend vcan1 111#05
sleep 0.5
kill $dump0; wait $dump0 2>/dev/null
check "after vcan0 was removed and made again, its frames reach the network" \
  test "$(grep -c ' 101#04' "$out/vcan1.log")" -eq 1
check "and frames from the network reach it" test "$(grep -c ' 111#05' "$out/vcan0-remade.log")" -eq 1

# 2. The peer goes away: bridge A keeps running and counts failed sends; the peer returns and traffic resumes.
kill -TERM $bridge_b; wait $bridge_b
for i in $(seq 1 20); do cansend vcan0 "102#$(printf '%02X' "$i")"; sleep 0.01; done
sleep 1.2
check "bridge A survives an unreachable peer" kill -0 $bridge_a
check "and reports the peer unreachable" test "$(tail -1 "$out/a.stats" | jq .to_network.peer_unreachable)" -gt 0
start_b
sleep 1
cansend vcan0 103#03
sleep 0.3
check "the restarted peer receives again (its new sequence numbers are accepted both ways)" \
  test "$(count 103)" -eq 1

# 3. A flood: memory stays bounded.
rss() { awk '/VmRSS/ { print $2 }' "/proc/$bridge_a/status"; }
# 20 kHz: twice a saturated 1 Mbit/s bus.
cangen vcan0 -I 104 -L 8 -D i -g 0.05 -n 2000
before=$(rss)
cangen vcan0 -I 105 -L 8 -D i -g 0.05 -n 20000
sleep 1
after=$(rss)
echo "bridge A resident memory: ${before} kB before, ${after} kB after 20000 more frames"
check "memory stays bounded (grew by less than 1 MB over 20000 frames)" test $((after - before)) -lt 1024

kill -TERM $bridge_a $bridge_b; wait $bridge_a; code=$?
kill $dump; wait $dump 2>/dev/null
check "bridge A exits 0 and flushes its recording" test "$code" -eq 0
recorded=$(grep -c ' 105#' "$work/a.log")
drops=$(tail -1 "$out/a.stats" | jq .can_rx_kernel_drops)
echo "flood: $recorded of 20000 recorded, $drops dropped by the kernel before the bridge read them"
check "every frame of the flood is recorded, or counted as a kernel drop" test $((recorded + drops)) -eq 20000
check "at 20 kHz nothing is dropped" test "$drops" -eq 0

finish "bridge survival"
