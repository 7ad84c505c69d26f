#!/usr/bin/env bash
# Runs inside the kernel rig with gpio-sim (tools/kernel-rig/run-in-guest --gpio-sim): the PWM motor's enable,
# direction and fault lines on a simulated chip (its PWM side on a temporary sysfs tree, as on the host);
# gpioinfo, libgpiod's own tool, checks the chip the tests use.
# usage: pwm_motor_gpio.sh BIN_DIR
set -uo pipefail
bin=$1
source "$(dirname "$0")/gpio_sim_lib.sh"

sim_chip motor mot-en mot-dir mot-fault || exit 1
"$bin/lever_tests_motor_gpio_sim" --durations yes
