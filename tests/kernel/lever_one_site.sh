#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time [--kvaser]): one
# site. The HSI's and the TOP's lever-fw on one CAN bus, each on its own gpio-sim chip (encoder lines, motor driver
# lines), its PWM chip, and for the TOP a Modbus TCP strain gauge, all played by lever-hil serve. lever-ctl homes
# and arms them as an operator would; candump records the run, which tools/dbc-decode reads back by
# the DBC alone.
# usage: lever_one_site.sh BIN_DIR [vcan|kvaser]
#   vcan    both levers on vcan0 (the default)
#   kvaser  the HSI on can0, the TOP on can1: the emulated SJA1000 controllers of run-in-guest --kvaser, on one
#           emulated bus at 1 Mbit/s, through Debian's sja1000 and kvaser_pci drivers
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
trap stop_all EXIT
site_bus=${2:-vcan}
kvaser_up() {  # kvaser_up IFC: an SJA1000 interface up at 1 Mbit/s, error-active
  local details
  details=$(ip -details link show "$1") && [[ $details == *"state ERROR-ACTIVE"* && $details == *"bitrate 1000000 "* ]]
}
case $site_bus in
  vcan) ;;
  kvaser)
    require "can0 is up at 1 Mbit/s, error-active" kvaser_up can0
    require "can1 is up at 1 Mbit/s, error-active" kvaser_up can1 ;;
  *) echo "lever_one_site.sh: the second argument must be vcan or kvaser (got '$site_bus')" >&2; exit 2 ;;
esac

one_site one-site --duration 15 --json --trace "$out/one-site.trace.csv"

require "both levers come up disarmed and not homed" wait_for 60 hsi '.state == "disarmed" and (.position_valid | not)'
require "(TOP too)" wait_for 60 top '.state == "disarmed" and (.position_valid | not)'
lever_ctl "$(site_can hsi)" arm; code=$?
check "arm before homing: lever-ctl says a lever refuses it, unhomed (exit $code)" \
  test "$code" -eq 1 -a "$(grep -c 'refused: .*unhomed' "$out/lever-ctl.log")" -eq 1
sleep 1
check "not armed unhomed" test "$(last_stat hsi .state)/$(last_stat top .state)" = disarmed/disarmed
require "lever-ctl home: both levers' heartbeats say homed" lever_ctl "$(site_can hsi)" home
require "the HSI homed against its end stop (its status line)" wait_for 120 hsi '.position_valid'
require "the TOP homed against its end stop" wait_for 120 top '.position_valid'
check "homed at the stop's position" \
  stat_true hsi '(.position_rad | num) > -0.7 and (.position_rad | num) < 0.5'
require "lever-ctl arm: both levers' heartbeats say armed" lever_ctl "$(site_can hsi)" arm
require "serve saw both armed heartbeats" wait_for_serve one-site "both levers armed"

check_one_site_run "$out/one-site.report"

kill -TERM "$hsi_pid" "$top_pid"
wait "$hsi_pid"; hsi_code=$?
wait "$top_pid"; top_code=$?
check "SIGTERM: lever-fw HSI exits 0 (got $hsi_code)" test "$hsi_code" -eq 0
check "SIGTERM: lever-fw TOP exits 0 (got $top_code)" test "$top_code" -eq 0
# Stopped is duty 0 with the PWM enabled, its inactive state: a disabled PWM's output is undefined.
check "and leaves its motor at zero duty, enabled: HSI $(pwm_state hsi)" test "$(pwm_state hsi)" = "1 0"
check "TOP $(pwm_state top)" test "$(pwm_state top)" = "1 0"
check "and the controllers' pins give the drivers no duty: HSI $(pwm_hw hsi)" pin_inactive hsi "$(pwm_hw hsi | cut -d' ' -f7)"
check "TOP $(pwm_hw top)" pin_inactive top "$(pwm_hw top | cut -d' ' -f7)"

sleep 0.5
"$dbc_decode" --summary "$dbc" "$out/one-site.candump" >"$work/decoded"; code=$?
jq -c '.messages | map_values(.frames)' "$work/decoded"
check "every frame candump logged decodes by the DBC (exit $code)" test "$code" -eq 0
check "the log holds both heartbeats, motion and force frames and the commands" \
  test "$(jq '.messages | has("LeverHeartbeatHsi") and has("LeverHeartbeatTop") and has("LeverMotion") and has("LeverForce") and has("LeverCommand")' "$work/decoded")" = true
check "as many force frames as serve counted, or more (it counts only while both are armed)" \
  test "$(jq .messages.LeverForce.frames "$work/decoded")" -ge "$(jq .frames.force "$out/one-site.report")"
states=$("$dbc_decode" "$dbc" "$out/one-site.candump" | awk '$3 == "LeverHeartbeatTop" { print $4 }' | uniq | tr '\n' ' ')
echo "TOP heartbeat states in the log: $states"
check "the TOP's heartbeats went from disarmed through homing (4) to armed (2)" grep -q "State=1 .*State=4 .*State=2" <<<"$states"
# lever-plot on the same recording: its frames per message are dbc-decode's, each lever's data frames its own count.
"$bin/lever-plot" "$out/one-site.candump" --status "$out/hsi.stats" --status "$out/top.stats" --out "$work/plot" \
  --no-plots >"$work/plot.out"; code=$?
check "lever-plot draws the recording (exit $code)" test "$code" -eq 0
for message in LeverMotion LeverForce LeverHeartbeatHsi LeverHeartbeatTop LeverCommand; do
  check "lever-plot counts the $message frames dbc-decode does" \
    grep -qE "^  $message +$(jq ".messages.$message.frames" "$work/decoded") " "$work/plot.out"
done
for role in HSI TOP; do
  check "lever-plot: the $role's data_sent and refresh_sent at its last status line are the log's" \
    grep -qE "^  $role at its last placed status line .*data_sent ([0-9]+), refresh_sent ([0-9]+); in the log by then: data \1, refresh \2$" "$work/plot.out"
done
finish "lever-fw one site"
