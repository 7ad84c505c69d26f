#!/usr/bin/env bash
# Runs inside the kernel rig with gpio-sim (tools/kernel-rig/run-in-guest --gpio-sim): the libgpiod encoder
# backend against a simulated chip whose lines lever-gpio-quadrature-gen drives; gpioinfo, libgpiod's own tool,
# checks the chip the tests use.
# usage: gpio_encoder.sh BIN_DIR
set -uo pipefail
bin=$1
rig=$(cd "$(dirname "$0")/../../tools/kernel-rig" && pwd)

chip_dev=$("$rig/gpio-sim-chip" enc enc-a enc-b enc-z) || exit 1
read -r chip dev <<<"$chip_dev"
info=$(gpioinfo "$chip")
echo "$info"
for name in enc-a enc-b enc-z; do
  grep -q "\"$name\" *unused *input" <<<"$info" || { echo "FAILED: gpioinfo shows no free input \"$name\"" >&2; exit 1; }
done

export LEVER_GPIO_CHIP=$chip LEVER_GPIO_LABEL=enc LEVER_GPIO_SYSFS=/sys/devices/platform/$dev/$chip
export LEVER_GPIO_GEN=$bin/lever-gpio-quadrature-gen
"$bin/lever_tests_gpio_sim" --durations yes
