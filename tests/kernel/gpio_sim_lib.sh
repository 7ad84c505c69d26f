# Sourced by the kernel-rig tests that need a gpio-sim chip (run-in-guest --gpio-sim).
# sim_chip LABEL LINE...: creates the chip with these named lines, checks with gpioinfo (libgpiod's own tool)
# that each is a free input, and exports LEVER_GPIO_CHIP, LEVER_GPIO_LABEL and LEVER_GPIO_SYSFS for the tests.
sim_chip() {
  local label=$1; shift
  local rig chip_dev chip dev info name
  rig=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../tools/kernel-rig" && pwd)
  chip_dev=$("$rig/gpio-sim-chip" "$label" "$@") || return 1
  read -r chip dev <<<"$chip_dev"
  info=$(gpioinfo "$chip")
  echo "$info"
  for name in "$@"; do
    grep -q "\"$name\" *unused *input" <<<"$info" || { echo "FAILED: gpioinfo shows no free input \"$name\"" >&2; return 1; }
  done
  export LEVER_GPIO_CHIP=$chip LEVER_GPIO_LABEL=$label LEVER_GPIO_SYSFS=/sys/devices/platform/$dev/$chip
}
