# Sourced by the tests that time a fault to a lever's safe state from its PWM controller's own stamps (the kernel
# rig's lever_faults.sh, the board image's tests/image/safety_units.sh), after lever_sites_lib.sh.

# clock_now: the guest's clock into $now, in microseconds: bash's own $EPOCHREALTIME, read without a fork or a
# file (a fork costs milliseconds of guest time and a read of /proc/timer_list near one, all of it counted). In
# virtual time (-rtc clock=vm) the guest's realtime clock runs with its monotonic one.
clock_now() { now=${EPOCHREALTIME/./}; }
# The kernel's own stamps, all on CLOCK_MONOTONIC (the PWM controllers' clock): tracefs with trace_clock mono,
# the gpio_value events of the levers' enable lines (the kernel stamps the line's change, so no poll's lateness
# counts), and this shell's marks (trace_marker). Only the enable lines' sets are traced: the encoders' reads are
# thousands a second, more than a poll could read. Reading the trace must not pause it (pause-on-trace), or a stop
# that comes while a poll reads it would go unstamped. trace_setup GPIO...: the enable lines' numbers.
tracing=/sys/kernel/tracing
trace_setup() {
  local filter='' gpio
  for gpio in "$@"; do filter+="${filter:+ || }gpio == $gpio"; done
  [[ -n $filter ]] || return 1
  [[ -w $tracing/trace_marker ]] || mount -t tracefs nodev "$tracing" || return 1
  echo 0 >"$tracing/events/gpio/gpio_value/enable" &&
    echo "get == 0 && ($filter)" >"$tracing/events/gpio/gpio_value/filter" &&
    echo mono >"$tracing/trace_clock" &&  # which also empties the buffer
    echo 0 >"$tracing/options/pause-on-trace" &&
    echo 1 >"$tracing/events/gpio/gpio_value/enable" &&
    echo 1 >"$tracing/tracing_on"
}
# trace_us LINE: $tus, the trace line's stamp in microseconds of CLOCK_MONOTONIC ("...  11.188203: event: ...")
trace_us() {
  local s=${1%%: *}
  s=${s##* }
  tus=$((${s%.*} * 1000000 + 10#${s#*.}))
}
# mark_stamp TEXT: $stamp, the newest trace mark TEXT (written to trace_marker) on clock_now's clock; empty if none
mark_stamp() {
  local line
  stamp=''
  while IFS= read -r line; do
    [[ $line == *": tracing_mark_write: $1" ]] || continue
    trace_us "$line"
    stamp=$((tus - offset_us))
  done <"$tracing/trace"
}
# mono_offset: CLOCK_MONOTONIC less $EPOCHREALTIME, in microseconds (to put the kernel's stamps on the test's
# clock): a trace mark's stamp between two clock_now, so within the cost of one small write. Sets up the tracing.
# Also has pin_inactive read, now rather than in a timed poll, which levers' boards invert their PWM, and each
# lever's enable line's number in the gpio_value events.
mono_offset() {
  local a b role base lines=() mono
  for role in hsi top; do
    [[ -r $work/$role.toml ]] && { pin_inactive "$role" 0 || :; }
    local gpio=${role}_gpio
    if [[ -n ${!gpio:-} ]]; then
      read -r base <"$(echo "${!gpio%/*}"/gpio/gpiochip*/base)" && printf -v "enable_gpio_$role" '%s' "$base"
      lines+=("$base")
    fi
  done
  trace_setup "${lines[@]}" || { check "tracefs: the kernel's stamps of the enable lines" false; return 1; }
  # Ten marks, then the trace read; the narrowest counts (one the loops preempted is only wider). Not at a
  # real-time priority: the chrt that would bring this shell back would start at it, and its start alone (a fork and
  # an exec, milliseconds here) would hold the loops off long enough to latch TIMING.
  local try best='' error before=() after=()
  for try in 0 1 2 3 4 5 6 7 8 9; do
    clock_now
    before[try]=$now
    echo "lever-test: clock $try" >"$tracing/trace_marker"
    clock_now
    after[try]=$now
  done
  offset_us=0
  for try in 0 1 2 3 4 5 6 7 8 9; do
    a=${before[try]} b=${after[try]}
    mark_stamp "lever-test: clock $try"
    if [[ -z $best ]] || ((b - a < best)); then best=$((b - a)) error=$(((b - a + 1) / 2)) mono=$((stamp - (a + b) / 2)); fi
  done
  offset_us=$mono
  echo "CLOCK_MONOTONIC - realtime: $offset_us us (+-$error us)"
}
# line_stamp ROLE T0: $stamp, the time (clock_now's clock) from which the lever's enable line has been low, as the
# kernel stamped its gpio_value events since T0 (the first of the last run of lows); empty when it was set high
# after its last low, or never set since T0
line_stamp() {
  local line number=enable_gpio_$1 value
  stamp=''
  [[ -n ${!number:-} ]] || return 0
  while IFS= read -r line; do
    [[ $line == *": gpio_value: ${!number} set "[01] ]] || continue
    trace_us "$line"
    ((tus - offset_us >= $2)) || continue
    value=${line##* }
    if ((value == 0)); then
      [[ -n $stamp ]] || stamp=$((tus - offset_us))
    else
      stamp=''
    fi
  done <"$tracing/trace"
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
# enable_low ROLE: the lever's driver enable line (MOTOR_EN, line 0 of its motor chip) low
enable_low() { local gpio=${1}_gpio value; read -r value <"${!gpio}/sim_gpio0/value" && [[ $value == 0 ]]; }
# poll_rt on|off: while it times a fault, the test's shell runs at SCHED_FIFO 50, below the levers (80) and above
# serve's world (an ordinary process), so that its polls are not queued behind the world's steps.
poll_rt() { if [[ $1 == on ]]; then chrt -f -p 50 $$; else chrt -o -p 0 $$; fi >/dev/null; }
# off_time CONDITION ROLE T0: when CONDITION (motor_off, pwm_inactive or enable_low), which holds now, began, from
# the kernel's stamps into $now, and $how says which: for pwm_inactive the controller's stamp; for enable_low the
# line's; for motor_off the earlier of the two (the motor has been off since then, as each has stayed off since its
# own). $now and $how are left as they are (the poll that saw it) when there is no stamp.
off_time() {
  local line_at='' pin_at=''
  case $1 in motor_off | pwm_inactive | enable_low) ;; *) return 0 ;; esac
  if [[ $1 != pwm_inactive ]]; then
    line_stamp "$2" "$3"
    line_at=$stamp
  fi
  if [[ $1 != enable_low ]]; then
    off_stamp "$2" "$3"
    pin_at=$stamp
  fi
  if [[ -n $line_at && (-z $pin_at || $line_at -le $pin_at) ]]; then
    now=$line_at how="the enable line's stamp"
  elif [[ -n $pin_at ]]; then
    now=$pin_at how="the controller's stamp"
  fi
}
# time_to NAME MIN_MS MAX_MS T0 CONDITION...: waits (polling each 0.2 ms of guest time, up to 5 s) until the
# condition holds, and checks the time from T0 (clock_now) to it is within [MIN_MS, MAX_MS]. For `motor_off ROLE`,
# `pwm_inactive ROLE` and `enable_low ROLE` the time is the kernel's own stamp of the change that stopped the motor
# (off_time); for any other condition, or with no stamp, the first poll that saw it.
time_to() {
  local name=$1 min=$2 max=$3 t0=$4
  shift 4
  local deadline=$((t0 + 5000000)) how=polled every=0.0002
  [[ $1 == motor_off || $1 == pwm_inactive || $1 == enable_low ]] && every=0.002  # stamped: the polls only wait
  while ! "$@"; do
    clock_now
    ((now < deadline)) || { check "$name: not reached within 5 s (bound $max ms)" false; return; }
    read -rt "$every" -u "$never_ready" || :
  done
  clock_now
  off_time "$1" "$2" "$t0"
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
# does nothing). The swing can also outrun a lever's edge queue (an encoder fault: its count lost, which only
# homing restores), so a lever that shows one is homed first, once.
both_armed() { [[ $(last_stat hsi '.state == "armed"') == true && $(last_stat top '.state == "armed"') == true ]]; }
count_lost() {
  [[ $(last_stat top '.faults | index("encoder") != null') == true ||
    $(last_stat hsi '.faults | index("encoder") != null') == true ]]
}
rearm() {
  local presses=0
  while ((presses < 20)); do
    if [[ $1 != *", homed" ]] && count_lost; then
      rehome "$1, a count lost"
      return
    fi
    command vcan0 3
    presses=$((presses + 1))
    sleep 1.5
    both_armed || continue
    sleep 1.5
    both_armed && break
  done
  require "re-armed after: $1 ($presses presses)" both_armed
}

# stat_lines ROLE: how many status lines the lever has printed; status_mark: each lever's count now, just after a
# fault, for recover
stat_lines() { local n=0 line; while IFS= read -r line; do n=$((n + 1)); done <"$out/$1.stats"; echo "$n"; }
status_mark() { mark_hsi=$(stat_lines hsi) mark_top=$(stat_lines top); }
# recover WHY: after a fault that may have cost a lever its count, once each lever has printed two status lines past
# status_mark (the second is wholly from after the fault: the loop publishes a snapshot every 100 ms, the printer the
# newest once a second; an encoder fault found when the loop runs again shows there), the pair re-armed (rearm
# homes a lever that lost its count)
recover() {
  local role mark deadline=$((SECONDS + 10))
  for role in hsi top; do
    mark=mark_$role
    while (($(stat_lines "$role") < ${!mark} + 2 && SECONDS < deadline)); do sleep 0.2; done
  done
  rearm "$1"
}

# rehome WHY: both levers disarmed (the HSI leaves its safe state, faults kept), homed and re-armed: what a lever
# whose count can no longer be trusted needs
rehome() {
  command vcan0 2
  command vcan0 6
  require "the pair homes again ($1)" wait_for 120 top '.position_valid'
  require "(the HSI too)" wait_for 120 hsi '.position_valid'
  rearm "$1, homed"
}

# motor_on ROLE: the lever drives torque at this moment, read from the hardware (not no_torque: its driver enabled
# and its PWM pin active); driver_on ROLE: its driver enabled (the enable line high), for the cases timed by that
# line. Checked just before each fault, so that a lever already safe (disarmed, faulted, at zero duty) cannot pass a
# time-to-safe check it never had to meet.
motor_on() { ! no_torque "$1"; }
driver_on() { ! enable_low "$1"; }
# until_on SECONDS ROLE...: polls every 0.2 ms until each lever named drives torque (motor_on) at the same moment,
# for up to SECONDS: the HSI shows no force in free space, so only while the operator presses the wall. The operator
# script's longest stretch off the wall is 1.35 s (wall-tap: a move away of at most 1.2 s with its dwell, then a
# thrust of at most 0.15 s), so a pair at work meets it within one such stretch; a miss says each lever's state.
until_on() {
  local seconds=$1 deadline=$((SECONDS + $1)) role all
  shift
  while ((SECONDS < deadline)); do
    all=1
    for role in "$@"; do motor_on "$role" || { all=0; break; }; done
    ((all)) && return 0
    read -rt 0.0002 -u "$never_ready" || :
  done
  for role in hsi top; do
    echo "not both on in $seconds s: the $role: its newest status line: $(last_stat "$role" '"\(.state), faults \(.faults)"')," \
      "motor on $(motor_on "$role" && echo yes || echo no), PWM $(pwm_state "$role")" >&2
  done
  return 1
}

# spin_and_time NAME MAX_MS: a process at SCHED_FIFO 80, the loops' own priority, spins 100 ms by its own clock on
# this one CPU; each lever's time to motor_off counts from the spinner's first act, a trace mark: from there no loop
# steps (a FIFO process that lowers itself to 80 runs at the head of that priority, and it never blocks), so each
# loop's last step, from which its guard counts, came before it. This shell forks it from SCHED_FIFO 99 and waits for
# it without polling: a poller above the guards (81) would delay them by its own polls. The motors' times come from
# the kernel's stamps (off_time). The loops' sched_switch events, which would time from the last step itself, are
# not traced: in the rig that tracing lost the events near the spin (docs/hil-serve.md).
spin_and_time() {
  local name=$1 max=$2 role spin_t0 forked
  chrt -f -p 99 $$ >/dev/null
  clock_now
  forked=$now
  chrt -f 80 bash -c 'echo "lever-test: spin" >'"$tracing"'/trace_marker
    end=$((${EPOCHREALTIME/./} + 100000)); while ((${EPOCHREALTIME/./} < end)); do :; done' 2>"$out/spinner.err" &
  wait "$!"
  local spun=$?
  chrt -f -p 50 $$ >/dev/null
  status_mark
  mark_stamp "lever-test: spin"
  spin_t0=$stamp
  if [[ -n $spin_t0 ]]; then
    echo "$name: the spinner started $(ms_since "$forked" "$spin_t0") ms after its fork"
    for role in hsi top; do time_to "$name: the $role's motor off" 0 "$max" "$spin_t0" motor_off "$role"; done
    return
  fi
  # A trace without the mark: from the fork instead, where a loop may still step while the spinner starts (so the
  # time is longer, never shorter, than from the mark)
  echo "the spinner's mark is missing: it exited $spun ($(<"$out/spinner.err")), tracing_on $(<"$tracing/tracing_on");" \
    "the trace's stats and first and last lines:" >&2
  grep -v '^#' "$tracing/per_cpu/cpu0/stats" >&2
  grep -v '^#' "$tracing/trace" | sed -n '1,5p;$p' >&2
  for role in hsi top; do
    time_to "$name: the $role's motor off, from the spinner's fork (its mark missing)" 0 "$max" "$forked" motor_off "$role"
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
