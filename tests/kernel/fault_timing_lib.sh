# Sourced by the tests that time a fault to a lever's safe state from its PWM controller's own stamps (the kernel
# rig's lever_faults.sh, the board image's tests/image/safety_units.sh), after lever_sites_lib.sh.

# clock_now: the guest's clock into $now, in microseconds: bash's own $EPOCHREALTIME, read without a fork or a
# file (a fork costs milliseconds of guest time and a read of /proc/timer_list near one, all of it counted). In
# virtual time (-rtc clock=vm) the guest's realtime clock runs with its monotonic one.
clock_now() { now=${EPOCHREALTIME/./}; }
# mono_offset: CLOCK_MONOTONIC less $EPOCHREALTIME, in microseconds (to put the controllers' stamps on the test's
# clock), read once: /proc/timer_list's "now at" between two clock_now. Also has pin_inactive read, now rather than
# in a timed poll, which levers' boards invert their PWM.
mono_offset() {
  local line a b role
  for role in hsi top; do [[ -r $work/$role.toml ]] && { pin_inactive "$role" 0 || :; }; done
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
# "+ms enabled period duty pin"
applied_since() {
  local n t e p d pin
  while read -r n t e p d pin; do
    ((t / 1000 - offset_us >= $2)) &&
      echo "  +$(ms_since "$2" $((t / 1000 - offset_us))) ms: enabled $e period $p duty $d, pin high ${pin} ppm"
  done <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/apply_log"
}
# off_stamp ROLE T0: $stamp, the time (clock_now's clock) of the state since T0 the lever's controller was
# programmed with from which its pin has given the driver no duty (the first of the last such run: a duty that
# passed through 0 before is not the stop); empty when there is none in its log
off_stamp() {
  local n t e p d pin
  stamp=''
  while read -r n t e p d pin; do
    ((t / 1000 - offset_us >= $2)) || continue
    if pin_inactive "$1" "$pin"; then
      [[ -n $stamp ]] || stamp=$((t / 1000 - offset_us))
    else
      stamp=''
    fi
  done <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/apply_log"
}
ms_since() { awk -v d=$(($2 - $1)) 'BEGIN { printf "%.2f", d / 1e3 }'; }  # ms_since T0 T1: (T1 - T0) in ms
# motor_off ROLE: no torque at the lever's driver, read from the hardware's outputs (no_torque: its PWM pin gives
# the driver no duty, or its enable line is low). lever-fw stops a motor with both (PwmMotor's release: the line,
# then duty 0 with the PWM enabled). Never the controller's enabled flag: a disabled PWM's pin may hold high. A held
# lever at a duty that rounds to 0 reads off too: no torque is no torque.
motor_off() { no_torque "$1"; }
# pwm_inactive ROLE: its PWM pin gives the driver no duty (what a process must write, since the kernel keeps a dead
# writer's state: duty 0 with the channel enabled), whatever the enable line does
pwm_inactive() {
  local enabled period duty polarity applies last pin
  read -r enabled period duty polarity applies last pin <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/hw_state" &&
    pin_inactive "$1" "$pin"
}
# enable_low ROLE: the lever's driver enable line (MOTOR_EN, line 2) low
enable_low() { local gpio=${1}_gpio value; read -r value <"${!gpio}/sim_gpio2/value" && [[ $value == 0 ]]; }
# poll_rt on|off: while it times a fault, the test's shell runs at SCHED_FIFO 50, below the levers (80) and above
# serve's world (an ordinary process), so that its polls are not queued behind the world's steps.
poll_rt() { if [[ $1 == on ]]; then chrt -f -p 50 $$; else chrt -o -p 0 $$; fi >/dev/null; }
# time_to NAME MIN_MS MAX_MS T0 CONDITION...: waits (polling each 0.2 ms of guest time, up to 5 s) until the
# condition holds, and checks the time from T0 (clock_now) to it is within [MIN_MS, MAX_MS]. For `motor_off ROLE`
# and `pwm_inactive ROLE` the time is the controller's own stamp of the state that stopped the motor (apply_log);
# when the motor stopped by its driver's enable line instead (no stamp), or for any other condition, it is the
# first poll that saw it.
time_to() {
  local name=$1 min=$2 max=$3 t0=$4
  shift 4
  local deadline=$((t0 + 5000000)) how=polled every=0.0002
  [[ $1 == motor_off || $1 == pwm_inactive ]] && every=0.002  # stamped: the polls only wait
  while ! "$@"; do
    clock_now
    ((now < deadline)) || { check "$name: not reached within 5 s (bound $max ms)" false; return; }
    read -rt "$every" -u "$never_ready" || :
  done
  clock_now
  if [[ $1 == motor_off || $1 == pwm_inactive ]]; then
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

# motor_on ROLE: the lever drives torque at this moment, read from the hardware (not no_torque: its driver enabled
# and its PWM pin active); driver_on ROLE: its driver enabled (the enable line high), for the cases timed by that
# line. Checked just before each fault, so that a lever already safe (disarmed, faulted, at zero duty) cannot pass a
# time-to-safe check it never had to meet.
motor_on() { ! no_torque "$1"; }
driver_on() { ! enable_low "$1"; }
# until_on SECONDS ROLE...: polls every 0.2 ms until each lever named drives torque (motor_on) at the same moment,
# for up to SECONDS: the HSI shows no force in free space, so only while the operator presses the wall
until_on() {
  local deadline=$((SECONDS + $1)) role all
  shift
  while ((SECONDS < deadline)); do
    all=1
    for role in "$@"; do motor_on "$role" || { all=0; break; }; done
    ((all)) && return 0
    read -rt 0.0002 -u "$never_ready" || :
  done
  return 1
}

# spin_and_time NAME MAX_MS: a process at SCHED_FIFO 80, the loops' own priority, spins 100 ms by its own clock on
# this one CPU, while this shell, at SCHED_FIFO 99 above everything, polls both levers' motors every 0.2 ms (a few
# tens of microseconds each, so the guards at 81 lose no more than that). Each lever's time to motor_off counts from
# just before the spinner is forked: the loops lose the CPU from there, to its start (forked at 99, then chrt and
# bash at 80) before its spin. Its controller's stamp where the stop changed the PWM's state, else the poll that saw it; each against MAX_MS.
# The shell goes back to FIFO 50 after.
spin_and_time() {
  local name=$1 max=$2 seen_hsi='' seen_top='' deadline spin_t0 role
  chrt -f -p 99 $$ >/dev/null
  clock_now
  spin_t0=$now
  chrt -f 80 bash -c 'end=$((${EPOCHREALTIME/./} + 100000)); while ((${EPOCHREALTIME/./} < end)); do :; done' &
  local spinner=$!
  deadline=$((now + 5000000))
  while [[ -z $seen_hsi || -z $seen_top ]] && ((now < deadline)); do
    read -rt 0.0002 -u "$never_ready" || :
    clock_now
    [[ -z $seen_hsi ]] && motor_off hsi && seen_hsi=$now
    [[ -z $seen_top ]] && motor_off top && seen_top=$now
  done
  wait "$spinner"
  chrt -f -p 50 $$ >/dev/null
  for role in hsi top; do
    local seen=seen_$role how=polled ms
    if [[ -z ${!seen} ]]; then
      check "$name: the $role's motor off: not reached within 5 s (bound $max ms)" false
      continue
    fi
    now=${!seen}
    off_stamp "$role" "$spin_t0"
    [[ -n $stamp ]] && ((stamp <= now)) && now=$stamp how="the controller's stamp"
    ms=$(ms_since "$spin_t0" "$now")
    check "$name: the $role's motor off: $ms ms, $how (bound <= $max ms)" \
      awk -v m="$ms" -v hi="$max" 'BEGIN { exit !(m >= 0 && m <= hi) }'
    fault_rows+=("| $name: the $role's motor | <= $max | $ms | $how |")
  done
}

# kill_guard_and_time ROLE LEVER_PID: kills the lever's motor guard (lever-fw's only child; sets $guard_pid) with
# the lever driving torque, and times lever-fw's own stop of its motor (its SIGCHLD handler). Bound, term by term:
# the guard's exit, as this shell sees it (time_after_exit); then SIGCHLD delivered to lever-fw and its handler
# run, 0.2 ms; the enable line's ioctl and the PWM's two writes, the last stamped by the controller, 0.3 ms. The
# exit is measured, not assumed: the kernel tears the guard's locked memory down before its parent hears of it.
kill_guard_and_time() {
  local role=$1 lever=$2 t0
  guard_pid=''
  read -r guard_pid <"/proc/$lever/task/$lever/children"
  require "the $role's motor guard is lever-fw's child (pid ${guard_pid:-none})" test -n "$guard_pid"
  poll_rt on
  check "before its guard is killed: the $role's motor on" until_on 5 "$role"
  clock_now
  t0=$now
  kill -KILL "$guard_pid"
  time_after_exit "the $role's motor guard killed: lever-fw stops its motor itself" "$guard_pid" 0.5 "$t0" "$role"
  poll_rt off
}

# exited PID: the process has ended: reaped already, or a zombie with no thread left but its first (the first
# thread's own end comes first, while the others still tear down; its pidfd is readable only after them)
exited() {
  local key value rest state='' threads=''
  [[ -r /proc/$1/status ]] || return 0
  while read -r key value rest; do
    case $key in State:) state=$value ;; Threads:) threads=$value ;; esac
  done 2>/dev/null <"/proc/$1/status" || return 0
  [[ -z $state || ($state == Z && $threads == 1) ]]
}
# time_after_exit NAME PID AFTER_MS T0 ROLE [CAP_MS]: polls (0.2 ms) until process PID has ended, then checks that
# ROLE's motor was off (motor_off, timed as time_to does) within AFTER_MS of that end, as this shell saw it, or
# within CAP_MS of T0 if that is sooner (the guard's deadline, which a dead lever's loop misses too). The shell runs
# below the levers and their guards, so it sees the end after them: the bound only loosens by its delay. For the
# deaths whose first term is the kernel's own work on the dying process (its threads, its locked memory and its
# files torn down before its pidfd or its parent hears of it), which depends on its size and is measured here.
time_after_exit() {
  local name=$1 pid=$2 after=$3 t0=$4 role=$5 cap=${6:-} deadline
  clock_now
  deadline=$((now + 5000000))
  until exited "$pid"; do
    ((now < deadline)) || { check "$name: process $pid did not end within 5 s" false; return; }
    read -rt 0.0002 -u "$never_ready" || :
    clock_now
  done
  local ended=$now
  echo "$name: process $pid ended $(ms_since "$t0" "$ended") ms after the signal (as this shell saw it)"
  time_to "$name" 0 "$(awk -v e="$(ms_since "$t0" "$ended")" -v a="$after" -v c="$cap" \
    'BEGIN { b = e + a; if (c != "" && c + 0 < b) b = c + 0; printf "%.2f", b }')" "$t0" motor_off "$role"
}
