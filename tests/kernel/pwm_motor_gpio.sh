#!/usr/bin/env bash
# Runs inside the kernel rig with gpio-sim (tools/kernel-rig/run-in-guest --gpio-sim): the PWM motor's enable,
# direction and fault lines on a simulated chip (its PWM side on a temporary sysfs tree, as on the host);
# gpioinfo, libgpiod's own tool, checks the chip the tests use.
# usage: pwm_motor_gpio.sh BIN_DIR
set -uo pipefail
bin=$1
rig=$(cd "$(dirname "$0")/../../tools/kernel-rig" && pwd)

chip_dev=$("$rig/gpio-sim-chip" motor mot-en mot-dir mot-fault) || exit 1
read -r chip dev <<<"$chip_dev"
info=$(gpioinfo "$chip")
echo "$info"
for name in mot-en mot-dir mot-fault; do
  grep -q "\"$name\" *unused" <<<"$info" || { echo "FAILED: gpioinfo shows no free line \"$name\"" >&2; exit 1; }
done

export LEVER_GPIO_CHIP=$chip LEVER_GPIO_LABEL=motor LEVER_GPIO_SYSFS=/sys/devices/platform/$dev/$chip
"$bin/lever_tests_motor_gpio_sim" --durations yes
