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

# 4. Tare: to the TOP only, once its settings frame is heard (docs/can-protocol.md: mode 0, changes 0, tares 0,
# p 1000, floor 50, filter 0). After the first copy the TOP says it is averaging (no resend while it does), 0.3 s
# later one more tare done: exit 0 on one command frame.
top_settings=0000E80332000000 top_taring=0040E80332000000 top_tared=0001E80332000000
echo "$disarmed" >"$work/top"; echo "$top_settings" >"$work/top_settings"
lever 141 "$work/top_settings"
watch_commands "$work/tare.log" 1 "$work/top_settings" "$top_taring"
(
  until [[ $(<"$work/top_settings") == "$top_taring" ]]; do sleep 0.02; done
  sleep 0.3
  echo "$top_tared" >"$work/top_settings"
) &
pids+=("$!")
ctl tare --pair 0 --can vcan0; code=$?
sleep 0.3
echo "  $(said)"
check "tare: exit 0 (got $code), done, one copy to the TOP alone (080#0402...), none while it averaged" \
  test "$code" -eq 0 -a "$(grep -c '^080#0402000000000000$' "$work/tare.log")" -eq 1 -a "$(wc -l <"$work/tare.log")" -eq 1
check "(the report says done, with the TOP's tare count)" grep -q "tare pair 0 on vcan0: done in .*tares 1" "$work/ctl.out"

# 5. set-deadband of the force direction (predictive, p 0.025, floor 0.05): to the TOP alone; the TOP takes the
# second copy (changes 1, the commanded values): exit 0 on two command frames.
top_set=0501FA0032000000
watch_commands "$work/deadband.log" 2 "$work/top_settings" "$top_set"
ctl set-deadband --pair 0 --can vcan0 --direction force --mode predictive --p 0.025 --floor 0.05; code=$?
sleep 0.3
echo "  $(said)"; echo "  frames: $(tr '\n' ' ' <"$work/deadband.log")"
check "set-deadband: exit 0 (got $code), done after two copies to the TOP alone (080#050EFA00...)" \
  test "$code" -eq 0 -a "$(tr '\n' ' ' <"$work/deadband.log")" = "080#050EFA0032000000 080#050EFA0032000000 "
check "(the report says done, with the TOP's settings)" \
  grep -q "set-deadband pair 0 on vcan0: done in .*force: predictive p 0.0250, floor 0.050 N" "$work/ctl.out"
# ... and a TOP that never takes it: exit 1 within the timeout, saying what its settings frame still shows.
watch_commands "$work/ignored.log"
ctl set-deadband --pair 0 --can vcan0 --direction force --p 0.1 --timeout 1; code=$?
echo "  $(said)"
check "set-deadband not taken: exit 1 (got $code), resent, naming the TOP and what it shows" \
  test "$code" -eq 1 -a "$(wc -l <"$work/ignored.log")" -ge 5
check "(the message)" grep -q "set-deadband pair 0: not done within 1 s .*TOP: its settings frame says force: predictive p 0.0250.*has not arrived" "$work/ctl.err"
check "no command ends unconfirmed" bash -c "! grep -q 'not confirmed' '$work/ctl.out' '$work/ctl.err'"

# 6. Bad input: an interface that does not exist, a pair out of range: exit 2, one line.
ctl arm --pair 0 --can nosuch0; code=$?
check "an interface that does not exist: exit 2 (got $code), one line: $(said)" \
  test "$code" -eq 2 -a "$(wc -l <"$work/ctl.err")" -eq 1
ctl arm --pair 16 --can vcan0; code=$?
check "--pair 16: exit 2 (got $code), one line: $(said)" test "$code" -eq 2 -a "$(wc -l <"$work/ctl.err")" -eq 1
finish "lever-ctl on vcan0"
