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
# latches ENCODER as well, and only homing again makes it whole. A stop longer than the motor guard's deadline is cut
# by the guard first (board/motor_guard.hpp: no step for guard_deadline_ms, found at its next check, every
# guard_check_ms; then a wake at SCHED_FIFO above every other thread and three writes, within 1 ms): the bound is
# the sooner of the two.
guard_deadline_ms=10 guard_check_ms=2
for stop_ms in 4 20 50; do
  poll_rt on
  check "before the ${stop_ms} ms stop: the TOP's motor on" until_on 5 top
  stop_top "0.0$(printf '%02d' "$stop_ms")"
  stop=$(ms_since 0 "$stopped_us")
  require "a stop longer than fault_after_ms: $stop ms" awk -v s="$stop" -v b="$fault_after_ms" 'BEGIN { exit !(s > b) }'
  time_to "TOP stopped for $stop ms: its motor off" 0 \
    "$(awk -v s="$stop" -v g=$((guard_deadline_ms + guard_check_ms + 1)) 'BEGIN { b = s + 2; if (g < b) b = g; printf "%.1f", b }')" \
    "$t0" motor_off top
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
check "before vcan0 down: the HSI's motor on, the TOP's driver on" eval 'until_on 5 hsi && driver_on top'
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

# 3. The gauge's amplifier gone (serve closes its Modbus server) and back: the TOP's force goes stale. The fault's
# moment is serve's own stamp of the server closed (its thread joined, so a reply in flight has been sent): serve is
# an ordinary process and takes the signal a tick or more after kill sent it, which is not the TOP's time. The
# bound, from that stamp, term by term (top.toml's figures, 1 ms ticks):
#   the last good sample arrived at or before the stamp;
#   + stale_ms + 1: stale once a sample is older than stale_ms whole ticks (strain_gauge.hpp: now - last > stale);
#   + 1: its age is floored to whole ticks (gauge_port.hpp), so its tick is rounded up by up to one;
#   + hold_ms: the TOP holds that long from the tick it latched FORCE_STALE, then commands zero torque;
#   + 1: that step's wake lateness and its write of the enable line low (its release), within a period;
#   + 0.2: this shell's poll of the line (a line has no stamp), every 0.2 ms at SCHED_FIFO 50.
# No sooner than hold_ms: a sample is at most poll_us + timeout_us (15 ms) older than the stamp, well inside stale_ms.
poll_rt on
check "before the gauge server goes: the TOP's driver on" driver_on top
kill -USR1 "$serve_pid"
require "serve stopped the gauge" wait_for_serve faults "gauge stopped (CLOCK_MONOTONIC"
closed_ns=$(sed -n 's/.*gauge stopped (CLOCK_MONOTONIC \([0-9]*\) ns).*/\1/p' "$out/faults.serve" | tail -n 1)
t0=$((closed_ns / 1000 - offset_us))
time_to "gauge server gone: the TOP holds, then releases its driver" "$hold_ms" \
  "$(awk -v s="$stale_ms" -v h="$hold_ms" 'BEGIN { print s + 1 + 1 + h + 1 + 0.2 }')" "$t0" enable_low top
poll_rt off
check "gauge server gone: the TOP latched FORCE_STALE" wait_for 5 top '.faults | index("force_stale") != null'
kill -USR2 "$serve_pid"
require "the gauge serves again" wait_for_serve faults "gauge serves again"
sleep 0.5
rearm "gauge server back"

# 4. The TOP killed: nothing of it runs any more. Its motor guard, which holds the enable line's request and the
# PWM's files, sees its pidfd and stops the motor. Bound, term by term: the kernel ends the process (its threads,
# its memory, locked, and its files) before the pidfd is readable: measured here (time_after_exit); the guard, at
# SCHED_FIFO above the loops, wakes at once on this one CPU: 0.1 ms; the line's ioctl and the two PWM writes, the
# last one stamped by the controller: 0.3 ms. The end is measured, not assumed: lever-fw's memory, every thread's
# stack included, is locked (mlockall) and torn down first. Then, as the service manager's ExecStopPost does, lever-fw --motor-off stops
# it again: its configuration was cut in half while it ran (an edit, a full disk; here the cut falls in a comment,
# so the rest is valid TOML whose motor keys are the defaults: the HSI's PWM chip): --motor-off stops the motor the
# lever's motor state names (--motor-state, written at its start), not the configuration's. The HSI hears the TOP
# fall silent.
cp "$work/top.toml" "$work/top.toml.whole"
head -c "$(($(wc -c <"$work/top.toml") / 2))" "$work/top.toml.whole" >"$work/top.toml"
poll_rt on
check "before SIGKILL: both motors on" until_on 5 hsi top
clock_now
t0=$now
kill -KILL "$top_pid"
time_after_exit "TOP killed: its guard stops its motor" "$top_pid" 0.4 "$t0" top \
  $((guard_deadline_ms + guard_check_ms + 1))
wait "$top_pid" 2>/dev/null  # reaped: systemd runs ExecStopPost after that
lever-fw --config "$work/top.toml" --motor-state "$out/top.motor" --motor-off >>"$out/top.err" 2>&1
motor_off_code=$?
check "and after it the TOP's PWM pin is at its inactive level (duty 0, enabled): $(pwm_hw top)" pwm_inactive top
# The HSI's bound: its comms timeout from the TOP's last frame (before t0), one period for the comparison and one for
# the step's phase; and one term of this rig, where both levers share one CPU: the dying TOP's teardown (its locked
# memory, its line requests) runs in the kernel at the TOP's SCHED_FIFO 80, the HSI loop's own priority, so it holds
# the HSI's steps off (hundreds of ms of it, as the end above shows). A hold-off longer than the HSI guard's deadline
# stops the HSI's motor by its guard, so the most it can delay the stop is the guard's own bound.
time_to "TOP killed: HSI motor off" 0 $((comms_ms + 2 * tick_ms + guard_deadline_ms + guard_check_ms + 1)) "$t0" \
  motor_off hsi
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

# 4b. The TOP's motor guard killed: the lever hears it end (SIGCHLD), stops its motor in the handler (the enable
# line's ioctl and the PWM's writes) and exits 1, for the service manager to start it again with a new guard.
kill_guard_and_time top "$top_pid"
wait "$top_pid" 2>/dev/null
top_code=$?
check "and the TOP exits 1 (got $top_code)" test "$top_code" -eq 1
check "and says why" has_text "$out/top.err" "the motor guard (pid $guard_pid) ended"
restart_top "after its guard was killed"

# 4c. A loop spinning at its real-time priority on this one CPU: a process at SCHED_FIFO 80, the loops' own
# priority, spins for 100 ms; neither loop steps, nor serve, nor this shell, nor PID 1. The guards, one priority
# above, still run: each stops its motor within its deadline, found at its next check, and 1 ms (as for a stop).
# Without the guards both would stay on until the spin ends and the loops find the gap: 100 ms.
poll_rt on
check "before the spin: both motors on" until_on 5 hsi top
spin_and_time "a FIFO 80 process spins 100 ms: its guard" $((guard_deadline_ms + guard_check_ms + 1))
poll_rt off
check "and the HSI's guard says so" has_text "$out/hsi.err" "loop has not stepped for"
check "and the TOP's guard says so" has_text "$out/top.err" "loop has not stepped for"
check "and the TOP latched TIMING" wait_for 5 top '.faults | index("timing") != null'
check "and the HSI latched TIMING" wait_for 5 hsi '.faults | index("timing") != null'
recover "after the spin"

# 5. The TOP's PWM channel unexported under lever-fw: its writes fail; the controller itself runs on at its last
# state, so the safe state is the driver's enable line going low, which PwmMotor does in the command whose write
# failed. It writes a changed duty at once and an unchanged one every PwmMotor::kConfirmEvery (10) commands (a
# TOP at rest against the wall holds one duty): so within 10 periods of the unexport, and one more for its phase.
# Here the TOP is at work and its duty changes within that too; lever_unexport_at_rest.sh is the case at rest.
poll_rt on
check "before the unexport: the TOP's driver on" driver_on top
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
check "before its chip goes: the HSI's motor on" until_on 5 hsi
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
