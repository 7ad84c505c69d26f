#!/usr/bin/env bash
# Runs inside the kernel rig with gpio-sim (tools/kernel-rig/run-in-guest --gpio-sim): the HIL's simulated
# encoder lines and motor readback (hil/devices) against the board layer's GpioEncoder and PwmMotor on two simulated
# chips; gpioinfo, libgpiod's own tool, checks each chip.
# usage: hil_devices.sh BIN_DIR
set -uo pipefail
bin=$1
source "$(dirname "$0")/gpio_sim_lib.sh"

sim_chip hil-enc enc-a enc-b enc-z || exit 1
export LEVER_ENC_CHIP=$LEVER_GPIO_LABEL
sim_chip hil-mot mot-en mot-dir mot-fault || exit 1
export LEVER_MOT_CHIP=$LEVER_GPIO_LABEL
"$bin/lever_tests_hil_devices_gpio_sim" --durations yes
