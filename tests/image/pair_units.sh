#!/usr/bin/env bash
# Runs on the reference board image (tools/board-image/boot, virtual time): the pair as a user runs it. The
# packages installed by apt, the levers started by systemd (`systemctl start lever-fw@hsi lever-fw@top`) as
# user lever, with the example configurations in /etc/lever where only the device keys are changed; the gpio-sim
# chips and the PWM controllers given to group gpio by the package's udev rule alone; the world (lever-hil serve,
# from lever-tools) as in lever_one_site.sh, and its one-site bounds.
# usage: pair_units.sh
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/units_lib.sh"
trap stop_units EXIT

board_devices || exit 1
one_site one-site --duration 15 --json --trace "$out/one-site.trace.csv"
check_unit_user hsi
check_unit_user top

require "both levers come up disarmed and not homed" wait_for 60 hsi '.state == "disarmed" and (.position_valid | not)'
require "(TOP too)" wait_for 60 top '.state == "disarmed" and (.position_valid | not)'
command vcan0 6
require "lever-ctl home: the HSI homes against its end stop" wait_for 120 hsi '.position_valid'
require "lever-ctl home: the TOP homes against its end stop" wait_for 120 top '.position_valid'
command vcan0 1
require "lever-ctl arm: both arm (serve saw both armed heartbeats)" wait_for_serve one-site "both levers armed"
wait "$serve_pid"; code=$?
check "lever-hil serve ran its 15 s scenario and exited 0 (got $code)" test "$code" -eq 0
check_one_site_report "$out/one-site.report"
check "no encoder edge lost" test "$(last_stat hsi .encoder.lost)/$(last_stat top .encoder.lost)" = 0/0
for role in hsi top; do
  read -r hw_enabled hw_period hw_duty hw_polarity hw_applies hw_last_ns <<<"$(pwm_hw $role)"
  check "$role: its PWM controller was programmed through the kernel's PWM core: $hw_applies states" \
    test "$hw_period $hw_polarity" = "50000 normal" -a "$hw_applies" -gt 100
done

systemctl stop lever-fw@hsi lever-fw@top
for role in hsi top; do
  check "systemctl stop lever-fw@$role: it exited 0 ($(unit_result "$role"))" \
    test "$(unit_result "$role")" = "success 0"
  check "and its motor is disabled at zero duty: $(pwm_state $role)" test "$(pwm_state $role)" = "0 0"
  check "and so is its controller: $(pwm_hw $role)" test "$(pwm_hw $role | cut -d' ' -f1,3)" = "0 0"
done
finish "the pair under systemd on the board image"
