#!/usr/bin/env bash
# Self-test of the kernel rig: boots the guest four times (about 10 s each under TCG).
#   1. can-utils as real peers on vcan0; vcan1 present; a vxcan pair and a can-gw route carry frames
#   2. a command's exit code (3) comes back as run-in-guest's exit code
#   3. --gpio-sim: gpio-sim-chip makes a chip whose named lines libgpiod's tools see and pull writes drive
#   4. --kvaser: can0 and can1 at 1 Mbit/s with the SJA1000's bit timing; a frame crosses from one to the other
# usage: tools/kernel-rig/selftest.sh      exit 0 when all pass; last line "N passed, N failed"
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
[[ ${1:-} == -h || ${1:-} == --help ]] && { awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$0"; exit 0; }

passed=0 failed=0
check() {   # check NAME EXPECTED_RC ACTUAL_RC
  if [[ $2 == "$3" ]]; then
    echo "PASS: $1"
    passed=$((passed + 1))
  else
    echo "FAIL: $1 (exit code $3, expected $2)"
    failed=$((failed + 1))
  fi
}

# Runs inside the guest, as root, in the host's tree (read-only) with $LEVER_RIG_OUT writable.
# shellcheck disable=SC2016  # expanded in the guest, not here
guest_script='
set -u
fail=0
candump -L vcan0 >"$LEVER_RIG_OUT/dump.log" &
dump=$!
sleep 0.5   # candump must have bound its socket before the frame goes out
cansend vcan0 123#DEADBEEF
sleep 0.5
kill "$dump"
wait "$dump" 2>/dev/null
if grep -q "vcan0 123#DEADBEEF" "$LEVER_RIG_OUT/dump.log"; then
  echo "guest: candump saw the frame cansend sent: $(cat "$LEVER_RIG_OUT/dump.log")"
else
  echo "guest: candump did not log 123#DEADBEEF; its log:" >&2
  cat "$LEVER_RIG_OUT/dump.log" >&2
  fail=1
fi

if ip link show vcan1 >/dev/null; then
  echo "guest: vcan1 exists"
else
  echo "guest: no vcan1" >&2
  fail=1
fi

if ip link add vxcan-a type vxcan peer name vxcan-b 2>"$LEVER_RIG_OUT/vxcan.err"; then
  ip link set up vxcan-a && ip link set up vxcan-b
  candump -L vxcan-b >"$LEVER_RIG_OUT/vxcan.log" &
  dump=$!
  sleep 0.5
  cansend vxcan-a 456#CAFE
  sleep 0.5
  kill "$dump"
  wait "$dump" 2>/dev/null
  if grep -q "vxcan-b 456#CAFE" "$LEVER_RIG_OUT/vxcan.log"; then
    echo "guest: vxcan pair works (frame sent on vxcan-a seen on vxcan-b)"
  else
    echo "guest: vxcan pair made but the frame did not cross it" >&2
    fail=1
  fi
  ip link del vxcan-a
else
  echo "guest: vxcan NOT available: $(cat "$LEVER_RIG_OUT/vxcan.err")" >&2
  fail=1
fi

# can-gw as a router: frames into vcan0 come out of vcan1.
if cangw -A -s vcan0 -d vcan1 -e 2>"$LEVER_RIG_OUT/cangw.err"; then
  candump -L vcan1 >"$LEVER_RIG_OUT/gw.log" &
  dump=$!
  sleep 0.5
  cansend vcan0 789#0102
  sleep 0.5
  kill "$dump"
  wait "$dump" 2>/dev/null
  if grep -q "vcan1 789#0102" "$LEVER_RIG_OUT/gw.log"; then
    echo "guest: can-gw routes vcan0 -> vcan1"
  else
    echo "guest: can-gw rule added but the frame did not reach vcan1" >&2
    fail=1
  fi
  cangw -F
else
  echo "guest: can-gw NOT available: $(cat "$LEVER_RIG_OUT/cangw.err")" >&2
  fail=1
fi
exit $fail
'

echo "== CAN peers on vcan0, vcan1, a vxcan pair, a can-gw route"
"$here/run-in-guest" --timeout 300 -- bash -c "$guest_script"
check "can-utils, vcan0/vcan1, vxcan, can-gw in the guest" 0 $?

echo "== exit code of the command comes back"
"$here/run-in-guest" --timeout 300 -- sh -c 'echo "guest: exiting 3"; exit 3'
check "run-in-guest exits 3 when the command does" 3 $?

# shellcheck disable=SC2016  # expanded in the guest, not here
gpio_script='
set -eu
helper=$1
set -- $("$helper" rigtest alpha beta)
chip=$1 dev=$2
gpioinfo "$chip" | grep -q "\"beta\"" || { echo "guest: gpioinfo does not name line 1 beta" >&2; exit 1; }
pull=/sys/devices/platform/$dev/$chip/sim_gpio1/pull
echo pull-up >"$pull"
[ "$(gpioget "$chip" 1)" = 1 ] || { echo "guest: pull-up did not read 1" >&2; exit 1; }
echo pull-down >"$pull"
[ "$(gpioget "$chip" 1)" = 0 ] || { echo "guest: pull-down did not read 0" >&2; exit 1; }
"$helper" --remove rigtest
echo "guest: gpio-sim chip $chip ($dev): named lines, driven by pull writes, removed"
'
echo "== gpio-sim: a simulated chip driven through sysfs, read with libgpiod's tools"
"$here/run-in-guest" --timeout 300 --gpio-sim -- bash -c "$gpio_script" gpio-selftest "$here/gpio-sim-chip"
check "gpio-sim chip made, named, driven and removed in the guest" 0 $?

# shellcheck disable=SC2016  # expanded in the guest, not here
kvaser_script='
set -u
for ifc in can0 can1; do
  details=$(ip -details link show "$ifc") || { echo "guest: no $ifc" >&2; exit 1; }
  for want in "bitrate 1000000" "sample-point" "sja1000:" "state ERROR-ACTIVE"; do
    grep -q "$want" <<<"$details" || { echo "guest: $ifc: no \"$want\" in:" >&2; echo "$details" >&2; exit 1; }
  done
done
candump -L can1 >"$LEVER_RIG_OUT/kvaser.log" &
dump=$!
sleep 0.5
cansend can0 321#C0FFEE
sleep 0.5
kill "$dump"
wait "$dump" 2>/dev/null
grep -q "can1 321#C0FFEE" "$LEVER_RIG_OUT/kvaser.log" || { echo "guest: can1 did not receive the frame can0 sent" >&2; exit 1; }
echo "guest: can0 and can1 at 1 Mbit/s (sja1000 timing), a frame crossed the emulated bus"
'
echo "== --kvaser: two emulated Kvaser PCI controllers on one bus"
"$here/run-in-guest" --timeout 300 --kvaser -- bash -c "$kvaser_script"
check "Kvaser PCI controllers at 1 Mbit/s carry a frame in the guest" 0 $?

echo "$passed passed, $failed failed"
((failed == 0))
