#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): faults injected
# on the real interfaces of a pair at work (one site, the operator tapping the wall), each timed from the
# injection to the lever's safe state as its motor shows it, against a bound from the configuration:
#   the TOP stopped (SIGSTOP) for less than a period (no fault: the timing budget spends it) and for 4, 20 and
#   50 ms; the CAN interface down and up again; the Modbus gauge server gone and back; the TOP killed (SIGKILL)
#   and its motor stopped by `lever-fw --motor-off` (its configuration cut in half meanwhile), as the service's
#   ExecStopPost does; the TOP's PWM channel
#   unexported under it; the HSI's gpio-sim chip removed.
# The safe state, read from the devices: the HSI's motor off (its PWM controller disabled or at duty 0, or its
# driver's enable line low); for the TOP the same, and where its rule is to hold for safe_hold_ms first, no sooner.
# After each fault that a re-arm can clear, the pair is re-armed and the next one comes.
# usage: lever_faults.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
trap stop_all EXIT

pin_tool ip || exit 1
one_site faults --duration 0 --json
up_and_homed
command vcan0 1
require "both arm" wait_for_serve faults "both levers armed"
pin_tool lever-fw "$bin/lever-fw" || exit 1  # for --motor-off, started as fast as a service manager would

# The configuration's figures the bounds come from.
key() { awk -v section="[$2]" -v key="$3" '/^\[/ { s = ($1 == section) } s && $1 == key { print $3; exit }' "$work/$1.toml"; }
comms_ms=$(key top link comms_timeout_ms)
stale_ms=$(key top gauge stale_ms)
tick_ms=1
echo "bounds from top.toml: comms timeout $comms_ms ms, stale gauge $stale_ms ms"

# clock_now: the guest's clock into $now, in microseconds: bash's own $EPOCHREALTIME, read without a fork or a
# file (a fork costs milliseconds of guest time and a read of /proc/timer_list near one, all of it counted). In
# virtual time (-rtc clock=vm) the guest's realtime clock runs with its monotonic one.
clock_now() { now=${EPOCHREALTIME/./}; }
# mono_offset: CLOCK_MONOTONIC less $EPOCHREALTIME, in microseconds (to put the controllers' stamps on the test's
# clock), read once: /proc/timer_list's "now at" between two clock_now
mono_offset() {
  local line a b
  clock_now
  a=$now
  while read -r line; do [[ $line == "now at "* ]] && break; done </proc/timer_list
  clock_now
  b=$now
  line=${line#now at }
  offset_us=$((${line%% *} / 1000 - (a + b) / 2))
  echo "CLOCK_MONOTONIC - realtime: $offset_us us (+-$(((b - a) / 2)) us)"
}
# applied_since ROLE T0: the states the lever's controller was programmed with since T0 (clock_now), as
# "+ms enabled period duty"
applied_since() {
  local n t e p d
  while read -r n t e p d; do
    ((t / 1000 - offset_us >= $2)) && echo "  +$(ms_since "$2" $((t / 1000 - offset_us))) ms: enabled $e period $p duty $d"
  done <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/apply_log"
}
# off_stamp ROLE T0: $stamp, the time (clock_now's clock) of the first state since T0 the lever's controller was
# programmed with that stops the motor (disabled); empty when there is none in its log
off_stamp() {
  local n t e p d
  stamp=''
  while read -r n t e p d; do
    ((t / 1000 - offset_us >= $2)) && [[ $e == 0 ]] && { stamp=$((t / 1000 - offset_us)); return; }
  done <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/apply_log"
}
ms_since() { awk -v d=$(($2 - $1)) 'BEGIN { printf "%.2f", d / 1e3 }'; }  # ms_since T0 T1: (T1 - T0) in ms
# motor_off ROLE: its controller disabled or its driver's enable line (MOTOR_EN, line 2) low. lever-fw stops a
# motor with both (PwmMotor's release); a held lever is enabled, even at a duty that rounds to 0.
motor_off() {
  local enabled period duty rest value=1
  read -r enabled period duty rest <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/hw_state" || return 1
  local gpio=${1}_gpio
  [[ -r ${!gpio}/sim_gpio2/value ]] && read -r value <"${!gpio}/sim_gpio2/value"
  [[ $enabled == 0 || $value == 0 ]]
}
top_enable_low() { local value; read -r value <"$top_gpio/sim_gpio2/value" && [[ $value == 0 ]]; }
# poll_rt on|off: while it times a fault, the test's shell runs at SCHED_FIFO 50, below the levers (80) and above
# serve's world (an ordinary process), so that its polls are not queued behind the world's steps.
poll_rt() { if [[ $1 == on ]]; then chrt -f -p 50 $$; else chrt -o -p 0 $$; fi >/dev/null; }
# time_to NAME MIN_MS MAX_MS T0 CONDITION...: waits (polling each 0.2 ms of guest time, up to 5 s) until the
# condition holds, and checks the time from T0 (clock_now) to it is within [MIN_MS, MAX_MS]. For `motor_off ROLE`
# the time is the controller's own stamp of the state that stopped the motor (apply_log); when the motor stopped
# by its driver's enable line instead (no stamp), or for any other condition, it is the first poll that saw it.
time_to() {
  local name=$1 min=$2 max=$3 t0=$4
  shift 4
  local deadline=$((t0 + 5000000)) how=polled every=0.0002
  [[ $1 == motor_off ]] && every=0.002  # stamped: the polls only wait
  while ! "$@"; do
    clock_now
    ((now < deadline)) || { check "$name: not reached within 5 s (bound $max ms)" false; return; }
    read -rt "$every" -u "$never_ready" || :
  done
  clock_now
  if [[ $1 == motor_off ]]; then
    off_stamp "$2" "$t0"
    [[ -n $stamp ]] && now=$stamp how="the controller's stamp"
  fi
  local ms bound="<= $max"
  ((min > 0)) && bound="$min..$max"
  ms=$(ms_since "$t0" "$now")
  check "$name: $ms ms, $how (bound $bound ms)" awk -v m="$ms" -v lo="$min" -v hi="$max" 'BEGIN { exit !(m >= lo && m <= hi) }'
  fault_rows+=("| $name | $bound | $ms | $how |")
}
fault_rows=()
# rearm WHY: both levers armed again, the operator still at work. Without its force feedback serve's operator,
# who taps a wall the TOP no longer shows, swings the HSI past the wall, and past its allowed range, where it
# refuses to arm; a re-arm while the HSI is inside the wall has the TOP push the wall at its torque limit until
# that latches. So, as an operator would, the re-arm is pressed again until the pair stays armed: both armed in
# status lines written 1.5 s after a press, and still 1.5 s later (at most 20 presses; a re-arm of an armed lever
# does nothing).
both_armed() { [[ $(last_stat hsi '.state == "armed"') == true && $(last_stat top '.state == "armed"') == true ]]; }
rearm() {
  local presses=0
  while ((presses < 20)); do
    command vcan0 3
    presses=$((presses + 1))
    sleep 1.5
    both_armed || continue
    sleep 1.5
    both_armed && break
  done
  require "re-armed after: $1 ($presses presses)" both_armed
}

# rehome WHY: both levers disarmed (the HSI leaves its safe state, faults kept), homed and re-armed: what a lever
# whose count can no longer be trusted needs
rehome() {
  command vcan0 2
  command vcan0 6
  require "the TOP homes again ($1)" wait_for 120 top '.position_valid'
  rearm "$1, homed"
}

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
# where it was for safe_hold_ms, then lets go (so its motor stops no sooner than that).
hold_ms=$(key top safety safe_hold_ms)
poll_rt on
clock_now
t0=$now
ip link set vcan0 down
time_to "vcan0 down: HSI motor off" 0 $((comms_ms + 2 * tick_ms)) "$t0" motor_off hsi
time_to "vcan0 down: the TOP holds, then its motor off" "$hold_ms" $((comms_ms + hold_ms + 2 * tick_ms)) "$t0" \
  motor_off top
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
time_to "gauge server gone: the TOP holds, then its motor off" "$hold_ms" $((stale_ms + hold_ms + 2 * tick_ms)) "$t0" \
  motor_off top
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
poll_rt on
clock_now
before=$now
echo 0 >/sys/class/pwm/pwmchip"$(pwm_chip top)"/unexport
clock_now
t0=$now  # the channel is gone once the kernel has removed it: the lever's time counts from there
echo "the unexport took $(ms_since "$before" "$t0") ms in the kernel"
time_to "TOP's PWM unexported: its driver disabled (enable line low)" 0 $(((10 + 1) * tick_ms)) "$t0" top_enable_low
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
