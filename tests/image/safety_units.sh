#!/usr/bin/env bash
# Runs on the reference board image (tools/board-image/boot, virtual time): the safety path under lever-fw@.service
# as shipped, the pair at work (one site, armed), each fault timed to the TOP's safe state from its PWM
# controller's own stamps (fault_timing_lib.sh), against a bound from the unit and the configuration:
#   1. the TOP's loop hung (SIGSTOP): systemd's WatchdogSec fires (SIGABRT, then SIGCONT), the motor off within
#      WatchdogSec + 50 ms (the feeder looks every quarter of it, docs/deploy.md); Restart=on-failure brings the
#      lever back disarmed and unhomed;
#   2. the TOP killed (SIGKILL): ExecStopPost's lever-fw --motor-off puts the PWM at duty 0 (enabled: the pin's
#      inactive level; a disabled one's output is undefined), which the kernel keeps as the
#      dead writer left it, and the world holds the released enable line where it was (as most GPIO controllers
#      do); bound: the unit's own budget for a lever whose loop no longer commands its motor, WatchdogSec + 50 ms,
#      the same as for a hung loop (docs/deploy.md, "The reference board image", says why not lever_faults.sh's
#      100 ms for a --motor-off started directly);
#   3. a third crash within StartLimitIntervalSec: the unit stays failed, the motor off;
#   4. a configuration error (exit 2): not retried.
# And systemd-analyze security of the running unit.
# usage: safety_units.sh
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/units_lib.sh"
. "$kernel_tests/fault_timing_lib.sh"
trap stop_units EXIT

unit_value() { systemctl show -p "$2" --value "lever-fw@$1"; }  # unit_value ROLE PROPERTY
timespan_ms() { systemd-analyze timespan "$1" | awk '$1 == "μs:" { print $2 / 1000 }'; }
main_pid() { printf -v "${1}_pid" '%s' "$(unit_value "$1" MainPID)"; }
# restarted ROLE PID: the unit runs again, with another main process than PID
restarted() { [[ $(unit_value "$1" ActiveState) == active && $(unit_value "$1" MainPID) != "$2" && $(unit_value "$1" MainPID) != 0 ]]; }
wait_until() {  # wait_until SECONDS COMMAND...: until the command succeeds (guest time)
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do ((SECONDS < deadline)) || return 1; sleep 0.2; done
}

board_devices || exit 1
one_site faults --duration 0 --json
check_unit_user top
up_and_homed
command vcan0 1
require "both arm" wait_for_serve faults "both levers armed"

systemd-analyze security --no-pager lever-fw@top.service >"$out/security.txt" 2>&1
exposure=$(grep -o 'Overall exposure level for lever-fw@top.service: [0-9.]*' "$out/security.txt" | awk '{ print $NF }')
# What the unit leaves open, each with its reason in the unit's comments (the whole table: security.txt).
grep '^✗' "$out/security.txt" | awk '{ printf "  open: %s (%s)\n", $2, $NF }'
# The package test holds the unit file's offline exposure at 2.0; the running unit must be no worse.
check "systemd-analyze security lever-fw@top (running): exposure $exposure <= 2.0" \
  awk -v e="${exposure:-99}" 'BEGIN { exit !(e <= 2.0) }'

watchdog_ms=$(timespan_ms "$(unit_value top WatchdogUSec)")
restart_s=$(($(timespan_ms "$(unit_value top RestartUSec)" | cut -d. -f1) / 1000))
echo "from the unit: WatchdogSec $watchdog_ms ms, RestartSec $restart_s s, StartLimitBurst $(unit_value top StartLimitBurst)"
mono_offset

# 1. The loop hung: the process stopped, as a loop stuck in a step would look to the feeder.
pid=$top_pid
poll_rt on
clock_now
t0=$now
kill -STOP "$top_pid"
# The unit's budget for a lever whose loop no longer commands its motor: hung (the feeder looks every quarter of
# WatchdogSec) or killed (systemd runs ExecStopPost at once).
uncommanded_ms=$(awk -v w="$watchdog_ms" 'BEGIN { print w + 50 }')
time_to "TOP's loop hung (SIGSTOP): systemd's watchdog, motor off" 0 "$uncommanded_ms" \
  "$t0" motor_off top
poll_rt off
applied_since top "$t0"
check "systemd said the watchdog fired" wait_until 10 grep -q "Watchdog timeout" <(journalctl -u lever-fw@top -o cat)
require "Restart=on-failure: lever-fw@top runs again ($((restart_s)) s later)" wait_until $((restart_s + 30)) restarted top "$pid"
main_pid top
require "and comes back disarmed and unhomed" wait_for 60 top '.state == "disarmed" and (.position_valid | not)'
check "restarts so far: 1 ($(unit_value top NRestarts))" test "$(unit_value top NRestarts)" = 1
rehome "restarted after the watchdog"

# 2. SIGKILL: nothing of lever-fw runs; the PWM keeps its duty until ExecStopPost's lever-fw --motor-off.
pid=$top_pid
poll_rt on
clock_now
t0=$now
kill -KILL "$top_pid"
# The kernel releases the dead process's lines, and the world holds the enable line where it was (as most GPIO
# controllers keep a released output); the PWM keeps its duty: the motor runs until ExecStopPost's lever-fw
# --motor-off disables it.
time_to "TOP killed (SIGKILL): ExecStopPost's lever-fw --motor-off, motor off" 0 "$uncommanded_ms" "$t0" motor_off top
time_to "TOP killed (SIGKILL): ExecStopPost's lever-fw --motor-off puts its PWM pin at the inactive level" 0 \
  "$uncommanded_ms" "$t0" pwm_inactive top
poll_rt off
applied_since top "$t0"
require "Restart=on-failure: lever-fw@top runs again" wait_until $((restart_s + 30)) restarted top "$pid"
main_pid top
require "and comes back disarmed and unhomed" wait_for 60 top '.state == "disarmed" and (.position_valid | not)'
check "restarts so far: 2 ($(unit_value top NRestarts))" test "$(unit_value top NRestarts)" = 2
rehome "restarted after SIGKILL"

# 3. The third crash within StartLimitIntervalSec: no fourth start.
poll_rt on
clock_now
t0=$now
kill -KILL "$top_pid"
time_to "TOP killed a third time: motor off" 0 "$uncommanded_ms" "$t0" motor_off top
time_to "TOP killed a third time: ExecStopPost puts its PWM pin at the inactive level" 0 "$uncommanded_ms" "$t0" \
  pwm_inactive top
poll_rt off
sleep $((restart_s + 5))
# systemd keeps the last failure's Result (signal) and says why it refused the fourth start in the journal.
check "after three crashes the unit stays failed ($(unit_value top ActiveState), no main process: $(unit_value top MainPID))" \
  test "$(unit_value top ActiveState) $(unit_value top MainPID)" = "failed 0"
check "systemd refused a fourth start: $(journalctl -u lever-fw@top -o cat | grep -m1 'repeated too quickly')" \
  grep -q "Start request repeated too quickly" <(journalctl -u lever-fw@top -o cat)
check "and its motor stays off: $(pwm_hw top)" motor_off top

# 4. A configuration error: exit 2 at once, and not started again.
cp "$work/top.toml" "$work/bad.toml"
set_key "$work/bad.toml" board.motor pwm_chip '"one"' && install -m 0644 "$work/bad.toml" /etc/lever/bad.toml
lever-fw --config /etc/lever/bad.toml --check-config >/dev/null 2>&1
code=$?
require "lever-fw rejects /etc/lever/bad.toml (pwm_chip = \"one\") with exit 2 (got $code)" test "$code" -eq 2
systemctl start lever-fw@bad 2>/dev/null
sleep $((restart_s + 5))
check "lever-fw@bad: failed with exit 2, not restarted ($(unit_value bad Result) $(unit_value bad ExecMainStatus), restarts $(unit_value bad NRestarts))" \
  test "$(unit_value bad ActiveState) $(unit_value bad ExecMainStatus) $(unit_value bad NRestarts)" = "failed 2 0"

echo
echo "| fault under lever-fw@.service | bound (ms) | time to the safe state (ms) | timed by |"
echo "|---|---|---|---|"
printf '%s\n' "${fault_rows[@]}"
finish "the safety path under systemd on the board image"
