#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): one site, as lever_one_site.sh, and the TOP's
# lever-fw is killed with SIGKILL mid-run. The HSI must reach its safe state within its comms timeout. The TOP,
# started again, comes up disarmed and not homed, homes, and the pair works again after a re-arm.
# usage: lever_restart.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
trap stop_all EXIT

one_site restart --duration 0 --hands-off --json --trace "$out/restart.trace.csv"
up_and_homed
require "lever-ctl arm: both levers' heartbeats say armed" lever_ctl vcan0 arm
mark=$(log_mark "$out/restart.candump")
require "candump too: the HSI's heartbeat says armed" heard_armed "$out/restart.candump" "$mark" hsi
require "and the TOP's" heard_armed "$out/restart.candump" "$mark" top
sleep 2

kill -KILL "$top_pid"
wait "$top_pid" 2>/dev/null
check "SIGKILL of the TOP: the HSI faults on its silence" \
  wait_for 20 hsi '.state == "fault" and (.faults | index("comms_timeout") != null)'
require "and is safe: zero torque at its driver (its PWM pin or enable line)" wait_until_true 10 no_torque hsi
# A killed process cannot stop its motor: the PWM keeps its last duty until something else does (on a board,
# the service's ExecStopPost). Shown, not asserted: it is the hardware's state, not lever-fw's doing.
echo "the killed TOP's PWM (enable duty_cycle): $(pwm_state top); its controller: $(pwm_hw top)"

lines_before=$(wc -l <"$out/top.stats")
start_fw top
check "restarted, the TOP comes up disarmed and not homed" \
  wait_for 60 top '.state == "disarmed" and (.position_valid | not)'
check "(a fresh process: its own status lines)" test "$(wc -l <"$out/top.stats")" -gt "$lines_before"
require "lever-ctl home: the restarted TOP homes (the HSI, in fault, keeps its position)" lever_ctl vcan0 home
require "the TOP's status line says homed" wait_for 120 top '.position_valid'
check "the HSI stays in its safe state meanwhile" test "$(last_stat hsi .state)" = fault
check "lever-ctl rearm: both levers' heartbeats say armed again" lever_ctl vcan0 rearm
mark=$(log_mark "$out/restart.candump")
check "candump too: the HSI is armed again" heard_armed "$out/restart.candump" "$mark" hsi
check "and the restarted TOP" heard_armed "$out/restart.candump" "$mark" top
kill -TERM "$serve_pid"
wait "$serve_pid"; code=$?
check "lever-hil serve exits 0 on SIGTERM (got $code)" test "$code" -eq 0
finish "lever-fw restart"
