#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): faults injected
# on the real interfaces of a pair at work (one site, the operator tapping the wall), each timed from the
# injection to the lever's safe state as its motor shows it, against a bound from the configuration:
#   the TOP stopped (SIGSTOP) for less than a period (no fault: the timing budget spends it) and for 4, 20 and
#   50 ms; the CAN interface down and up again; the Modbus gauge server gone and back; the TOP killed (SIGKILL)
#   and its motor stopped by `lever-fw --motor-off` (its configuration cut in half meanwhile), as the service's
#   ExecStopPost does; the TOP's PWM channel
#   unexported under it; the HSI's gpio-sim chip removed.
# The safe state, read from the devices' outputs: the HSI's motor off (its PWM pin giving the driver no duty, or its
# driver's enable line low; never the controller's enabled flag, since the rig's controller holds a disabled pin
# where it was); for the TOP the same, and where its rule is to hold for safe_hold_ms first, no sooner.
# After each fault that a re-arm can clear, the pair is re-armed and the next one comes.
# usage: lever_faults.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
. "$(dirname "$0")/fault_timing_lib.sh"
trap stop_all EXIT

pin_tool ip || exit 1
one_site faults --duration 0 --json
up_and_homed
command vcan0 1
require "both arm" wait_for_serve faults "both levers armed"
pin_tool lever-fw "$bin/lever-fw" || exit 1  # for --motor-off, started as fast as a service manager would

# The configuration's figures the bounds come from.
comms_ms=$(key top link comms_timeout_ms)
stale_ms=$(key top gauge stale_ms)
tick_ms=1
echo "bounds from top.toml: comms timeout $comms_ms ms, stale gauge $stale_ms ms"

# 1. The TOP's process stopped: its loop finds the gap when it runs again. The rule (top.toml, [timing]): a step
# interval longer than fault_after_ms latches TIMING at once; a shorter late interval spends one period of the
# window's budget. Each stop is measured (from before SIGSTOP to after SIGCONT), and the bound counts from the
# TOP running again: its first step finds the gap and stops the motor (2 periods at most).
fault_after_ms=$(key top timing fault_after_ms)
mono_offset
stop_top() {  # stop_top SECONDS: SIGSTOP, a builtin sleep, SIGCONT; sets t0 and stopped_us
  clock_now
  t0=$now
  kill -STOP "$top_pid"
  sleep "$1"
  kill -CONT "$top_pid"
  clock_now
  stopped_us=$((now - t0))
}
# Below the bound: stopped for less than a period, the TOP loses at most one period, which its budget spends.
# Judged on status lines taken after the stop only: the first line printed after SIGCONT may carry a snapshot from
# before it (the loop publishes one every 100 ms, the printer prints the newest once a second), the second cannot.
stat_lines() { local n=0 line; while IFS= read -r line; do n=$((n + 1)); done <"$out/$1.stats"; echo "$n"; }
# wait_after SECONDS ROLE MARK CONDITION: the lever has printed 2 status lines past line MARK, and its newest
# satisfies the condition
wait_after() {
  local deadline=$((SECONDS + $1))
  while ((SECONDS < deadline)); do
    (($(stat_lines "$2") >= $3 + 2)) && break
    sleep 0.2
  done
  (($(stat_lines "$2") >= $3 + 2)) || { echo "no second status line of $2 after line $3 within $1 s" >&2; return 1; }
  [[ $(last_stat "$2" "$4") == true ]] || { echo "$2's status after the stop: $(last_line "$out/$2.stats")" >&2; return 1; }
}
stop_top 0.0004
mark=$(stat_lines top)
require "a stop shorter than a period ($(ms_since 0 "$stopped_us") ms)" test "$stopped_us" -lt 1000
check "TOP stopped for $(ms_since 0 "$stopped_us") ms: no TIMING, the TOP stays armed (status lines after the stop)" \
  wait_after 5 top "$mark" '.state == "armed" and (.faults | index("timing") == null)'
# Above it: TIMING at the first step, and the motor off. A lever moving while its process is stopped may also
# overflow the kernel's 16-event FIFO of an encoder line (the v1 GPIO interface's, fixed): its count is lost, it
# latches ENCODER as well, and only homing again makes it whole.
for stop_ms in 4 20 50; do
  poll_rt on
  stop_top "0.0$(printf '%02d' "$stop_ms")"
  stop=$(ms_since 0 "$stopped_us")
  require "a stop longer than fault_after_ms: $stop ms" awk -v s="$stop" -v b="$fault_after_ms" 'BEGIN { exit !(s > b) }'
  time_to "TOP stopped for $stop ms: its motor off" 0 "$(awk -v s="$stop" 'BEGIN { printf "%.1f", s + 2 }')" "$t0" \
    motor_off top
  poll_rt off
  applied_since top "$t0"
  check "and latches TIMING" wait_for 5 top '.faults | index("timing") != null'
  if [[ $(last_stat top '.faults | index("encoder") != null') == true ]]; then
    echo "the TOP lost encoder edges while it was stopped: $(last_stat top '.encoder | tojson')"
    rehome "SIGSTOP $stop_ms ms, the count lost"
  else
    rearm "SIGSTOP $stop_ms ms"
  fi
done

# 2. The CAN interface down for half a second: both levers hear nothing. The HSI stops its motor; the TOP holds
# where it was for safe_hold_ms, then lets go (so its motor stops no sooner than that). The TOP's end of the hold is
# its driver's enable line going low: a hold may sit at duty 0 (no torque at the pin, seen at 216.7 ms into a
# 500 ms hold), which motor_off rightly reads as no torque, and then the release writes no new PWM state at all.
hold_ms=$(key top safety safe_hold_ms)
poll_rt on
clock_now
t0=$now
ip link set vcan0 down
time_to "vcan0 down: HSI motor off" 0 $((comms_ms + 2 * tick_ms)) "$t0" motor_off hsi
time_to "vcan0 down: the TOP holds, then releases its driver" "$hold_ms" $((comms_ms + hold_ms + 2 * tick_ms)) "$t0" \
  enable_low top
poll_rt off
ip link set vcan0 up
check "vcan0 down: the HSI latched COMMS" wait_for 5 hsi '.faults | index("comms_timeout") != null'
check "vcan0 down: the TOP latched COMMS" wait_for 5 top '.faults | index("comms_timeout") != null'
rearm "vcan0 down and up"

# 3. The gauge's amplifier gone (serve closes its Modbus server) and back: the TOP's force goes stale.
poll_rt on
clock_now
t0=$now
kill -USR1 "$serve_pid"
time_to "gauge server gone: the TOP holds, then releases its driver" "$hold_ms" $((stale_ms + hold_ms + 2 * tick_ms)) \
  "$t0" enable_low top
poll_rt off
check "gauge server gone: the TOP latched FORCE_STALE" wait_for 5 top '.faults | index("force_stale") != null'
kill -USR2 "$serve_pid"
require "the gauge serves again" wait_for_serve faults "gauge serves again"
sleep 0.5
rearm "gauge server back"

# 4. The TOP killed: nothing of it runs any more; its motor keeps its last duty, and its driver's enable line its
# last level (serve's world holds a released line, as most GPIO controllers do: hil/devices motor_readback.hpp),
# until the service manager's ExecStopPost (lever-fw --motor-off) stops it. Its configuration was cut in half
# while it ran (an edit, a full disk; here the cut falls in a comment, so the rest is valid TOML whose motor keys
# are the defaults: the HSI's PWM chip): --motor-off stops the motor the lever's motor state names (--motor-state,
# written at its start), not the configuration's. The HSI hears the TOP fall silent.
cp "$work/top.toml" "$work/top.toml.whole"
head -c "$(($(wc -c <"$work/top.toml") / 2))" "$work/top.toml.whole" >"$work/top.toml"
poll_rt on
clock_now
t0=$now
kill -KILL "$top_pid"
wait "$top_pid" 2>/dev/null  # reaped, its lines released: systemd runs ExecStopPost after that
lever-fw --config "$work/top.toml" --motor-state "$out/top.motor" --motor-off >>"$out/top.err" 2>&1
motor_off_code=$?
time_to "TOP killed, then lever-fw --motor-off: TOP motor off" 0 100 "$t0" motor_off top
# The enable line alone would do above; the PWM, which the kernel keeps as the dead writer left it, must be at its
# inactive level too (duty 0, enabled: a PWM disabled while its pin was high holds it high).
time_to "TOP killed, then lever-fw --motor-off: TOP's PWM pin inactive" 0 100 "$t0" pwm_inactive top
time_to "TOP killed: HSI motor off" 0 $((comms_ms + 2 * tick_ms)) "$t0" motor_off hsi
poll_rt off
check "lever-fw --motor-off on a configuration cut in half: exit 0 (got $motor_off_code)" test "$motor_off_code" -eq 0
check "and it stopped the motor its state names" has_text "$out/top.err" "(named by the motor state $out/top.motor)"
mv "$work/top.toml.whole" "$work/top.toml"
restart_top() {  # restart_top WHY: a new TOP process, homed, and the pair re-armed
  start_fw top
  require "the TOP restarted ($1) comes up disarmed" wait_for 60 top '.state == "disarmed"'
  rehome "TOP restarted ($1)"
}
restart_top "after SIGKILL"

# 5. The TOP's PWM channel unexported under lever-fw: its writes fail; the controller itself runs on at its last
# state, so the safe state is the driver's enable line going low, which PwmMotor does in the command whose write
# failed. It writes a changed duty at once and an unchanged one every PwmMotor::kConfirmEvery (10) commands (a
# TOP at rest against the wall holds one duty): so within 10 periods of the unexport, and one more for its phase.
# Here the TOP is at work and its duty changes within that too; lever_unexport_at_rest.sh is the case at rest.
poll_rt on
clock_now
before=$now
echo 0 >/sys/class/pwm/pwmchip"$(pwm_chip top)"/unexport
clock_now
t0=$now  # the channel is gone once the kernel has removed it: the lever's time counts from there
echo "the unexport took $(ms_since "$before" "$t0") ms in the kernel"
time_to "TOP's PWM unexported: its driver disabled (enable line low)" 0 $(((10 + 1) * tick_ms)) "$t0" enable_low top
poll_rt off
check "and the TOP latched MOTOR_DRIVER" wait_for 5 top '.faults | index("motor_driver") != null'
echo "the TOP's controller after the unexport (it runs on): $(pwm_hw top)"
kill -TERM "$top_pid"
wait "$top_pid" 2>/dev/null
restart_top "after the unexport: it exports the channel again"

# 6. The HSI's gpio-sim chip removed: its encoder and driver lines are gone.
poll_rt on
clock_now
t0=$now
echo 0 >/sys/kernel/config/gpio-sim/hsi/live
time_to "HSI's gpio chip removed: HSI motor off" 0 $((2 * tick_ms)) "$t0" motor_off hsi
poll_rt off
check "and the HSI latched a fault naming the encoder" wait_for 5 hsi '.faults | index("encoder") != null'
grep -h 'gpio\|encoder\|line' "$out/hsi.err" | tail -n 3

echo
echo "| fault | bound (ms) | time to the safe state (ms) | timed by |"
echo "|---|---|---|---|"
printf '%s\n' "${fault_rows[@]}"
kill -TERM "$serve_pid" "$hsi_pid" 2>/dev/null
finish "lever-fw faults on real interfaces"
