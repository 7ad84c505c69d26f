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
check "and neither lever's motor guard fired while both started" no_guard_fired hsi top
command vcan0 6
require "lever-ctl home: the HSI homes against its end stop" wait_for 120 hsi '.position_valid'
require "lever-ctl home: the TOP homes against its end stop" wait_for 120 top '.position_valid'
quiet_followers
command vcan0 1
require "lever-ctl arm: both arm (serve saw both armed heartbeats)" wait_for_serve one-site "both levers armed"
wait "$serve_pid"; code=$?
require "the followers read the journal again" resume_followers "$out/hsi.stats" "$out/top.stats"
check_one_site_run "$out/one-site.report" "$code"

systemctl stop lever-fw@hsi lever-fw@top
for role in hsi top; do
  check "systemctl stop lever-fw@$role: it exited 0 ($(unit_result "$role"))" \
    test "$(unit_result "$role")" = "success 0"
  check "and its motor is at zero duty, enabled (the inactive state): $(pwm_state $role)" test "$(pwm_state $role)" = "1 0"
  check "and its controller's pin gives the driver no duty: $(pwm_hw $role)" \
    pin_inactive "$role" "$(pwm_hw $role | cut -d' ' -f7)"
done
finish "the pair under systemd on the board image"
