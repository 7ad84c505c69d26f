#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): faults injected
# on the real interfaces of a pair at work (one site, the operator tapping the wall), each timed from the
# injection to the lever's safe state as its motor shows it, against a bound from the configuration:
#   the TOP stopped (SIGSTOP) for 2, 4, 20 and 50 ms; the CAN interface down and up again; the Modbus gauge
#   server gone and back; the TOP killed (SIGKILL) and its motor stopped by `lever-fw --motor-off`, as the
#   service's ExecStopPost does; the TOP's PWM channel unexported under it; the HSI's gpio-sim chip removed.
# The safe state, read from the devices: the HSI's motor off (its PWM controller disabled or at duty 0, or its
# driver's enable line low); the TOP's hold begun (the controller at the hold torque's duty) or its motor off.
# After each fault that a re-arm can clear, the pair is re-armed and the next one comes.
# usage: lever_faults.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
trap stop_all EXIT

pin_tool ip || exit 1
one_site faults --duration 0 --json
require "both levers come up disarmed" wait_for 60 hsi '.state == "disarmed"'
require "(TOP too)" wait_for 60 top '.state == "disarmed"'
command vcan0 6
require "both home" wait_for 120 hsi '.position_valid'
require "(TOP too)" wait_for 120 top '.position_valid'
command vcan0 1
require "both arm" wait_for_serve faults "both levers armed"
pin_tool lever-fw "$bin/lever-fw" || exit 1  # for --motor-off, started as fast as a service manager would

# The configuration's figures the bounds come from.
key() { awk -v section="[$2]" -v key="$3" '/^\[/ { s = ($1 == section) } s && $1 == key { print $3; exit }' "$work/$1.toml"; }
comms_ms=$(key top link comms_timeout_ms)
stale_ms=$(key top gauge stale_ms)
hold_duty=$(awk -v t="$(key top safety safe_hold_torque_nm)" -v kt="$(key top board.motor torque_constant_nm_per_a)" \
  -v g="$(key top board.motor gear_ratio)" -v a="$(key top board.motor full_scale_current_a)" \
  -v p="$(key top board.motor period_ns)" 'BEGIN { printf "%d", t / (g * kt * a) * p + 0.5 }')
tick_ms=1
echo "bounds from top.toml: comms timeout $comms_ms ms, stale gauge $stale_ms ms, hold torque at duty $hold_duty ns"

# mono_ns: CLOCK_MONOTONIC, the PWM controllers' clock, read without starting a program
mono_ns() {
  local line
  while read -r line; do
    [[ $line == "now at "* ]] && { line=${line#now at }; echo "${line%% *}"; return; }
  done </proc/timer_list
}
# motor_off ROLE: its controller disabled or at duty 0, or its driver's enable line (MOTOR_EN, line 2) low
motor_off() {
  local enabled period duty rest value=1
  read -r enabled period duty rest <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/hw_state" || return 1
  local gpio=${1}_gpio
  [[ -r ${!gpio}/sim_gpio2/value ]] && read -r value <"${!gpio}/sim_gpio2/value"
  [[ $enabled == 0 || $duty == 0 || $value == 0 ]]
}
# top_safe: the TOP holds (its controller at the hold torque's duty) or its motor is off
top_safe() {
  local enabled period duty rest
  read -r enabled period duty rest <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip top)/hw_state" || return 1
  [[ $duty == "$hold_duty" ]] || motor_off top
}
# time_to NAME BOUND_MS T0 CONDITION...: polls the condition each 0.2 ms of guest time for up to 5 s, prints and
# checks the time from T0 (mono_ns) to the first poll that saw it
time_to() {
  local name=$1 bound=$2 t0=$3 now
  shift 3
  local deadline=$((t0 + 5000000000))
  while ! "$@"; do
    now=$(mono_ns)
    ((now < deadline)) || { check "$name: not reached within 5 s (bound $bound ms)" false; return; }
    read -rt 0.0002 -u "$never_ready" || :
  done
  now=$(mono_ns)
  local ms
  ms=$(awk -v d=$((now - t0)) 'BEGIN { printf "%.1f", d / 1e6 }')
  check "$name: $ms ms (bound $bound ms)" awk -v m="$ms" -v b="$bound" 'BEGIN { exit !(m <= b) }'
  results+=("| $name | $bound | $ms |")
}
results=()
rearm() {  # both levers armed again, the operator still at work
  command vcan0 3
  require "re-armed after: $1" wait_for 10 hsi '.state == "armed"'
  require "(TOP too)" wait_for 10 top '.state == "armed"'
  sleep 0.5
}

# 1. The TOP's process stopped: its loop misses the ticks, and on waking finds the gap (TIMING).
for stop_ms in 2 4 20 50; do
  printf -v stop_s '0.%03d' "$stop_ms"
  t0=$(mono_ns)
  kill -STOP "$top_pid"
  sleep "$stop_s"
  kill -CONT "$top_pid"
  time_to "TOP stopped for $stop_ms ms: TOP holds" $((stop_ms + 2 * tick_ms)) "$t0" top_safe
  check "and latches TIMING" wait_for 5 top '.faults | index("timing") != null'
  rearm "SIGSTOP $stop_ms ms"
done

# 2. The CAN interface down for half a second: both levers hear nothing.
t0=$(mono_ns)
ip link set vcan0 down
time_to "vcan0 down: HSI motor off" $((comms_ms + 2 * tick_ms)) "$t0" motor_off hsi
time_to "vcan0 down: TOP holds" $((comms_ms + 2 * tick_ms)) "$t0" top_safe
sleep 0.5
ip link set vcan0 up
check "vcan0 down: both latched COMMS" wait_for 5 hsi '.faults | index("comms_timeout") != null'
rearm "vcan0 down and up"

# 3. The gauge's amplifier gone (serve closes its Modbus server) and back.
t0=$(mono_ns)
kill -USR1 "$serve_pid"
time_to "gauge server gone: TOP holds" $((stale_ms + 2 * tick_ms)) "$t0" top_safe
check "gauge server gone: the TOP latched FORCE_STALE" wait_for 5 top '.faults | index("force_stale") != null'
kill -USR2 "$serve_pid"
require "the gauge serves again" wait_for_serve faults "gauge serves again"
sleep 0.5
rearm "gauge server back"

# 4. The TOP killed: nothing of it runs any more; its motor keeps its last duty until the service manager's
# ExecStopPost (lever-fw --motor-off) stops it. The HSI hears the TOP fall silent.
t0=$(mono_ns)
kill -KILL "$top_pid"
lever-fw --config "$work/top.toml" --motor-off >>"$out/top.err" 2>&1
time_to "TOP killed, then lever-fw --motor-off: TOP motor off" 100 "$t0" motor_off top
time_to "TOP killed: HSI motor off" $((comms_ms + 2 * tick_ms)) "$t0" motor_off hsi
wait "$top_pid" 2>/dev/null
restart_top() {  # restart_top WHY: a new TOP process, homed, and the pair re-armed
  start_fw top
  require "the TOP restarted ($1) comes up disarmed" wait_for 60 top '.state == "disarmed"'
  command vcan0 2  # disarm: the HSI leaves its safe state (faults kept), so that both can be homed
  command vcan0 6
  require "the restarted TOP homes" wait_for 120 top '.position_valid'
  rearm "TOP restarted ($1) and homed"
}
restart_top "after SIGKILL"

# 5. The TOP's PWM channel unexported under lever-fw: its writes fail; the controller itself runs on at its last
# state, so the safe state is the driver's enable line going low.
t0=$(mono_ns)
echo 0 >/sys/class/pwm/pwmchip"$(pwm_chip top)"/unexport
top_enable_low() { local value; read -r value <"$top_gpio/sim_gpio2/value" && [[ $value == 0 ]]; }
time_to "TOP's PWM unexported: its driver disabled (enable line low)" $((2 * tick_ms)) "$t0" top_enable_low
check "and the TOP latched MOTOR_DRIVER" wait_for 5 top '.faults | index("motor_driver") != null'
echo "the TOP's controller after the unexport (it runs on): $(pwm_hw top)"
kill -TERM "$top_pid"
wait "$top_pid" 2>/dev/null
restart_top "after the unexport: it exports the channel again"

# 6. The HSI's gpio-sim chip removed: its encoder and driver lines are gone.
t0=$(mono_ns)
echo 0 >/sys/kernel/config/gpio-sim/hsi/live
time_to "HSI's gpio chip removed: HSI motor off" $((2 * tick_ms)) "$t0" motor_off hsi
check "and the HSI latched a fault naming the encoder" wait_for 5 hsi '.faults | index("encoder") != null'
grep -h 'gpio\|encoder\|line' "$out/hsi.err" | tail -n 3

echo
echo "| fault | bound (ms) | time to the safe state (ms) |"
echo "|---|---|---|"
printf '%s\n' "${results[@]}"
kill -TERM "$serve_pid" "$hsi_pid" 2>/dev/null
finish "lever-fw faults on real interfaces"
