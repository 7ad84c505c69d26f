#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): two sites. The HSI's lever-fw on vcan0, the
# TOP's on vcan1 (its strain gauge on Modbus RTU over a pseudo-terminal), joined by two lever-bridges over UDP
# on loopback, where the kernel's netem delays every datagram by 20 ms and loses 2 %. Both run the time-domain
# passivity controller (control.passivity.mode = "tdpa"; issue 14), so its energy frames cross the link too. lever-hil serve plays
# both levers' world, hands off (the wall taps are lever_one_site.sh's; here it is the link). Then the link is cut (netem loss 100 %): both levers must go to their safe states, stay
# there when the link is back, and come back only by a re-arm.
# usage: lever_two_sites.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
trap stop_all EXIT

# Loopback carries only the bridges' datagrams here (the gauge is on the pty), so netem on lo is the link.
check "netem: 20 ms one-way delay, 2 % loss on the link" tc qdisc add dev lo root netem delay 20ms loss 2%
two_sites_keys=(control.passivity mode '"tdpa"')
two_sites two-sites --duration 0 --hands-off --json --trace "$out/two-sites.trace.csv"

require "both levers come up disarmed" wait_for 60 hsi '.state == "disarmed"'
require "(TOP too)" wait_for 60 top '.state == "disarmed"'
command vcan0 6
require "home, sent at the HSI's site: the HSI homes" wait_for 120 hsi '.position_valid'
require "and over the link, the TOP homes" wait_for 120 top '.position_valid'
mark=$(log_mark "$out/two-sites-hsi.candump")
command vcan0 1
require "arm, sent at the HSI's site: the HSI arms" heard_armed "$out/two-sites-hsi.candump" "$mark" hsi
require "and over the link, the TOP arms (its heartbeat relayed back)" heard_armed "$out/two-sites-hsi.candump" "$mark" top
sleep 5
check "the TOP's gauge answers over RTU ($(last_stat top .modbus.polls) polls, $(last_stat top .modbus.errors) errors)" \
  test "$(last_stat top '.modbus.polls > 50 and .modbus.timeouts == 0')" = true
check "the bridges carried the pair's frames both ways" \
  test "$(tail -n 1 "$out/bridge-top.stats" | jq '.from_network.frames > 100 and .to_network.frames > 100')" = true
check "netem lost some of them: the receiving bridge saw sequence gaps" \
  test "$(tail -n 1 "$out/bridge-top.stats" | jq '.from_network.sequence_gaps > 0')" = true
for role in hsi top; do
  check "$role: tdpa runs ($(last_stat $role .passivity.energy_sent) energy frames sent) and its port's observed energy is not negative" \
    test "$(last_stat $role '.passivity.mode == "tdpa" and .passivity.energy_sent > 0 and .passivity.observed_energy_j >= -1e-6')" = true
done

# The link cut: every datagram lost.
tc qdisc change dev lo root netem delay 20ms loss 100%
require "link cut: the HSI faults" wait_for 20 hsi '.state == "fault" and (.faults | index("comms_timeout") != null)'
require "link cut: the TOP faults" wait_for 20 top '.state == "fault" and (.faults | index("comms_timeout") != null)'
require "the HSI is safe: zero torque" wait_for 10 hsi '.torque_nm == 0'
require "the TOP is safe: its hold ends at zero torque" wait_for 10 top '.torque_nm == 0'
tc qdisc change dev lo root netem delay 20ms loss 2%
sleep 3
check "the link is back, and both stay in their safe states" \
  test "$(last_stat hsi .state)/$(last_stat top .state)" = fault/fault
mark=$(log_mark "$out/two-sites-hsi.candump")
command vcan0 3
check "re-arm: the HSI is armed again" heard_armed "$out/two-sites-hsi.candump" "$mark" hsi
check "re-arm: the TOP is armed again" heard_armed "$out/two-sites-hsi.candump" "$mark" top
sleep 3
check "and both stay armed (status lines after 3 s)" \
  test "$(last_stat hsi .state)/$(last_stat top .state)" = armed/armed

kill -TERM "$serve_pid"
wait "$serve_pid"; code=$?
check "lever-hil serve exits 0 on SIGTERM (got $code)" test "$code" -eq 0
report=$out/two-sites.report
jq . "$report"
r() { jq -r "$1" "$report"; }
# The script keeps the pair armed 5 s before the cut and 3 s after the re-arm, and the rest of the time is the
# harness's own pace: a fault of either lever in those spans cuts the 8 s short.
check "both armed for $(r .armed_s) s in all (at least the 8 s the script holds them armed)" \
  test "$(r '.armed_s > 7.9')" = true
# 25 mrad is what the TOP's saturated position loop allows (lever_one_site.sh); at rest the link adds nothing.
check "the TOP holds the HSI's position over the link: rms error $(r .position_rmse) rad < 0.025" \
  test "$(r '.position_rmse < 0.025')" = true
"$dbc_decode" --summary "$dbc" "$out/two-sites-hsi.candump" >"$work/decoded"; code=$?
jq -c '.messages | map_values(.frames)' "$work/decoded"
check "every frame on the HSI's bus decodes by the DBC, the TOP's relayed ones too (exit $code)" test "$code" -eq 0
check "the TOP's energy frames crossed the link to the HSI's bus" \
  test "$(jq '.messages.LeverEnergyTop.frames > 0' "$work/decoded")" = true
finish "lever-fw two sites"
