#!/usr/bin/env bash
# Runs inside the kernel rig with gpio-sim (tools/kernel-rig/run-in-guest --gpio-sim): the libgpiod encoder
# backend against a simulated chip whose lines lever-gpio-quadrature-gen drives; gpioinfo, libgpiod's own tool,
# checks the chip the tests use.
# usage: gpio_encoder.sh BIN_DIR
set -uo pipefail
bin=$1
source "$(dirname "$0")/gpio_sim_lib.sh"

sim_chip enc enc-a enc-b enc-z || exit 1
export LEVER_GPIO_GEN=$bin/lever-gpio-quadrature-gen
"$bin/lever_tests_gpio_sim" --durations yes
