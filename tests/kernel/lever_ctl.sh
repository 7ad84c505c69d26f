#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --virtual-time): lever-ctl on vcan0 against a pair
# played by can-utils. Each "lever" is a cansend loop sending the heartbeat in its file every 25 ms; a candump of
# the command id logs what lever-ctl sends and, as the levers would, changes their heartbeats after a given
# command frame. The real pair's tests (lever_two_sites.sh and the others) operate real lever-fw processes by it.
# usage: lever_ctl.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
# In virtual time a program read from the host over 9p lands late by the host's load while the guest's clock
# runs on to its next timer: the peers' heartbeats would come late by that. So, as for the pair tests, the
# programs that run again and again run from the guest's memory, and sleep is bash's own.
. "$(dirname "$0")/lever_sites_lib.sh"
pin_tool cansend || exit 1
pin_tool candump || exit 1
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; wait 2>/dev/null' EXIT

# Heartbeat payloads of pair 0 (docs/can-protocol.md): byte 0 the state (1 disarmed, 2 armed, 3 fault) with bit 4
# position valid, bytes 1-2 the latched faults.
disarmed=1100000000000000 armed=1200000000000000 fault_comms=1301000000000000
lever() {  # lever ID FILE: a heartbeat every 25 ms, the payload the file holds now
  while :; do cansend vcan0 "$1#$(<"$2")"; sleep 0.025; done &
  pids+=("$!")
}
# watch_commands LOG [N FILE PAYLOAD]...: log every command frame; after the Nth, FILE's lever says PAYLOAD
watch_commands() {
  local log=$1; shift
  local args=("$@")
  : >"$log"
  (
    n=0
    candump -L vcan0,080:7FF | while read -r _ _ frame; do
      n=$((n + 1))
      echo "$frame" >>"$log"
      for ((k = 0; k + 2 < ${#args[@]}; k += 3)); do
        ((n == args[k])) && echo "${args[k + 2]}" >"${args[k + 1]}"
      done
    done
  ) &
  pids+=("$!")
  sleep 0.2
}
ctl() { lever-ctl "$@" >"$work/ctl.out" 2>"$work/ctl.err"; }
said() { cat "$work/ctl.out" "$work/ctl.err"; }

# 1. Nobody answers: resent every 100 ms to both until the timeout, then exit 1 naming both levers.
watch_commands "$work/silent.log"
ctl arm --pair 0 --can vcan0 --timeout 1; code=$?
sleep 0.2
echo "  $(said)"
check "no lever heard: exit 1 (got $code), naming both" \
  test "$code" -eq 1 -a "$(grep -c "HSI: no heartbeat heard; TOP: no heartbeat heard" "$work/ctl.err")" -eq 1
check "(the message)" grep -q "HSI: no heartbeat heard; TOP: no heartbeat heard" "$work/ctl.err"
check "arm resent every 100 ms for 1 s: $(wc -l <"$work/silent.log") frames, each an arm to both (080#0103...)" \
  test "$(grep -c '^080#0103000000000000$' "$work/silent.log")" -ge 9 -a "$(wc -l <"$work/silent.log")" -le 11
kill "${pids[@]}" 2>/dev/null; wait 2>/dev/null; pids=()

# 2. The levers miss commands: the HSI arms on the first copy, the TOP only on the third. lever-ctl must
# resend, to the TOP alone once the HSI is armed, and stop when both say armed.
echo "$disarmed" >"$work/hsi"; echo "$disarmed" >"$work/top"
lever 700 "$work/hsi"; lever 701 "$work/top"
watch_commands "$work/lossy.log" 1 "$work/hsi" "$armed" 3 "$work/top" "$armed"
ctl arm --pair 0 --can vcan0; code=$?
sleep 0.3
echo "  $(said)"; echo "  frames: $(tr '\n' ' ' <"$work/lossy.log")"
check "both armed in the end: exit 0 (got $code), after 3 command frames" \
  grep -q "arm pair 0 on vcan0: done in .* 3 command frames" "$work/ctl.out"
check "the first to both, the resends to the TOP alone (080#0102...), and no more" \
  test "$(tr '\n' ' ' <"$work/lossy.log")" = "080#0103000000000000 080#0102000000000000 080#0102000000000000 "

# 3. A lever that refuses for good: the TOP in fault with COMMS latched. arm cannot clear it: exit 1 at once,
# naming the lever, its state and the fault.
echo "$fault_comms" >"$work/top"
sleep 0.1
ctl arm --pair 0 --can vcan0; code=$?
echo "  $(said)"
check "arm to a TOP in fault: exit 1 (got $code), naming the TOP, its state and fault" \
  grep -q "arm pair 0: TOP refused: fault, position valid, faults comms_timeout: arm does not clear" "$work/ctl.err"

# 4. Tare: to the TOP only, while disarmed, three copies; reported unconfirmed.
echo "$disarmed" >"$work/top"
watch_commands "$work/tare.log"
sleep 0.1
ctl tare --pair 0 --can vcan0; code=$?
sleep 0.3
echo "  $(said)"
check "tare: exit 0 (got $code), three copies to the TOP alone (080#0402...), said to be unconfirmed" \
  test "$code" -eq 0 -a "$(grep -c '^080#0402000000000000$' "$work/tare.log")" -eq 3 -a \
  "$(wc -l <"$work/tare.log")" -eq 3
check "(the report says so)" grep -q "not confirmed" "$work/ctl.out"

# 5. Bad input: an interface that does not exist, a pair out of range: exit 2, one line.
ctl arm --pair 0 --can nosuch0; code=$?
check "an interface that does not exist: exit 2 (got $code), one line: $(said)" \
  test "$code" -eq 2 -a "$(wc -l <"$work/ctl.err")" -eq 1
ctl arm --pair 16 --can vcan0; code=$?
check "--pair 16: exit 2 (got $code), one line: $(said)" test "$code" -eq 2 -a "$(wc -l <"$work/ctl.err")" -eq 1
finish "lever-ctl on vcan0"
