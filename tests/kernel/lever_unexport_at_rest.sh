#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): a lever's PWM
# channel unexported while the lever rests armed, holding one duty. lever_faults unexports the TOP's under a pair at
# work, whose duty changes every period, so any write fails at once and any code notices; at rest only PwmMotor's
# confirming write (an unchanged duty written again every PwmMotor::kConfirmEvery commands) meets the gone channel,
# and its release takes the driver's enable line low. Code that writes only a changed duty notices at the next
# change, or never. The operator keeps hands off (serve --hands-off): the HSI rests, armed, its driver enabled. Its
# display gain is 0 (control.display.gain), so it commands exactly zero torque, duty 0, for as long as it rests: a
# duty that moved inside the window below would let a lever without the confirming write pass. The TOP hunts between two encoder counts,
# its duty changing every few periods, so it is the HSI's channel that goes.
# usage: lever_unexport_at_rest.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
. "$(dirname "$0")/fault_timing_lib.sh"
trap stop_all EXIT

one_site_hsi_keys=(control.display gain 0.0)
one_site at-rest --duration 0 --json --hands-off
up_and_homed
require "lever-ctl arm: both armed" lever_ctl vcan0 arm
tick_ms=1  # the loop's period, 1 kHz
mono_offset

# held MS: the HSI's controller programmed with nothing new for the last MS ms (its own stamp of its last state),
# and its driver enabled (its enable line high; the PWM is enabled whether it drives or not)
held() {
  local enabled period duty polarity applies last_ns pin
  read -r enabled period duty polarity applies last_ns pin < <(pwm_hw hsi)
  clock_now
  ! enable_low hsi && ((now - (last_ns / 1000 - offset_us) >= $1 * 1000))
}
wait_held() {
  local deadline=$((SECONDS + 30))
  while ((SECONDS < deadline)); do held 30 && return 0; read -rt 0.001 -u "$never_ready" || :; done
  return 1
}

poll_rt on
require "the HSI rests armed, its driver enabled, one duty held: its controller unprogrammed for 30 ms" wait_held
held_state=$(pwm_hw hsi)
clock_now
before=$now
echo 0 >/sys/class/pwm/pwmchip"$(pwm_chip hsi)"/unexport
clock_now
t0=$now
echo "the HSI's controller before the unexport: $held_state; the unexport took $(ms_since "$before" "$t0") ms"
# The confirming write comes within kConfirmEvery (10) commands of the unexport, one more period for its phase.
time_to "HSI at rest, its PWM unexported: its driver disabled (enable line low)" 0 $(((10 + 1) * tick_ms)) "$t0" \
  enable_low hsi
poll_rt off
echo "the HSI's status after it: $(last_line "$out/hsi.stats" | jq -c '{state, faults, torque_nm, overruns, worst_step_interval_ms, worst_step_us}' 2>/dev/null)"
tail -n 4 "$out/hsi.err"
check "and the HSI latched MOTOR_DRIVER" wait_for 5 hsi '.faults | index("motor_driver") != null'
echo "the HSI's controller after the unexport (it runs on at its last state): $(pwm_hw hsi)"
finish "the HSI at rest, its PWM channel unexported"
