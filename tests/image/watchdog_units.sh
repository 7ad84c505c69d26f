#!/usr/bin/env bash
# Runs on the reference board image booted with an emulated i6300esb (tools/board-image/boot --watchdog): the
# board's hardware watchdog is systemd's (tools/board-image/board/.../lever-board-watchdog.conf: RuntimeWatchdogSec),
# armed by PID 1 with the levers running under their units; when nothing feeds it (the kernel stopped: a panic
# that does not reboot), the watchdog resets the board. The board boots twice: the first run stops the kernel,
# the second (the same test, started by the same unit after the reset) checks and reports.
# usage: watchdog_units.sh
set -uo pipefail
share=$LEVER_RIG_OUT
if [[ -f $share/watchdog-phase ]]; then
  . "$(cd "$(dirname "$0")/../kernel" && pwd)/lib.sh" /usr/bin
  read -r crashed_at timeout_s <"$share/watchdog-phase"
  booted_at=$(awk -v now="$EPOCHREALTIME" '{ printf "%.1f", now - $1 }' /proc/uptime)
  # A power-on on the console: the PC's firmware (amd64), or the kernel's first line where QEMU loads it with no
  # firmware of its own to print (arm64's virt).
  power_ons=$(grep -a -c -E 'SeaBIOS|Booting Linux on physical CPU' "$share/console.log")
  check "the board booted again after its kernel stopped ($power_ons power-ons on its console)" \
    test "$(grep -c 'Kernel panic' "$share/console.log")" -ge 1 -a "$power_ons" -ge 2
  # The i6300esb keeps a flag across the reset it caused, which its driver reports as WDIOF_CARDRESET (0x20).
  status=$(cat /sys/class/watchdog/watchdog0/bootstatus 2>/dev/null)
  check "and the watchdog says it reset the board: bootstatus $status (WDIOF_CARDRESET 32)" \
    test "$(( ${status:-0} & 32 ))" -eq 32
  # Not a bound: the next boot's clock includes the firmware and a boot whose disk reads, in virtual time, cost
  # guest time as the host's load makes them (tools/board-image/boot).
  echo "from the stop to the next boot's kernel, by the RTC: $(awk -v a="$crashed_at" -v b="$booted_at" 'BEGIN { printf "%.1f", b - a }') s (RuntimeWatchdogSec $timeout_s s)"
  finish "the board's hardware watchdog under systemd"
  exit
fi

here=$(cd "$(dirname "$0")" && pwd)
. "$here/units_lib.sh"
trap stop_units EXIT
board_devices || exit 1
udevadm settle
one_site watchdog --duration 0 --json
up_and_homed
command vcan0 1
require "both arm" wait_for_serve watchdog "both levers armed"
timeout_s=$(systemd-analyze timespan "$(systemctl show -p RuntimeWatchdogUSec --value)" | awk '$1 == "μs:" { print $2 / 1e6 }')
require "PID 1 feeds a hardware watchdog: RuntimeWatchdogSec $timeout_s s" awk -v t="${timeout_s:-0}" 'BEGIN { exit !(t > 0) }'
dev=/sys/class/watchdog/watchdog0
require "/dev/watchdog0 is QEMU's i6300esb ($(cat $dev/identity 2>/dev/null)), active ($(cat $dev/state 2>/dev/null)), timeout $(cat $dev/timeout 2>/dev/null) s" \
  test "$(cat $dev/identity 2>/dev/null)" = "i6300ESB timer" -a "$(cat $dev/state 2>/dev/null)" = active
# watchdog_device ROLE: board.watchdog.device of its configuration
watchdog_device() { /usr/bin/lever-fw --config "/etc/lever/$1.toml" --get board.watchdog.device; }
check "the pair runs under its units meanwhile ($(systemctl is-active lever-fw@hsi lever-fw@top | tr '\n' ' ')), board.watchdog.device empty in both ($(watchdog_device hsi) $(watchdog_device top))" \
  test "$(systemctl is-active lever-fw@hsi lever-fw@top | tr '\n' ' ')/$(watchdog_device hsi)/$(watchdog_device top)" = "active active //"
# Nothing feeds it from here: the kernel panics and, told not to reboot, spins.
echo "$EPOCHREALTIME $timeout_s" >"$share/watchdog-phase"
sync
echo "stopping the kernel (sysrq c, no reboot on panic)"
echo 0 >/proc/sys/kernel/panic
echo c >/proc/sysrq-trigger
sleep 60
echo "FAILED: still running 60 s after the panic" >&2
exit 1
