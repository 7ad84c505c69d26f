# Sourced by the tests on the reference board image (tests/image/*.sh, run by tools/board-image/boot): the kernel
# rig's pair harness (tests/kernel/lever_sites_lib.sh) with the levers as a user runs them. lever-fw is the
# package's /usr/bin/lever-fw started by systemd (lever-fw@ROLE.service, user lever), its configuration the
# installed example /etc/lever/ROLE.toml with only the device keys changed, its status lines read from the journal;
# the devices are made by root and handed to the lever user by the package's udev rule alone.
kernel_tests=$(cd "$(dirname "${BASH_SOURCE[0]}")/../kernel" && pwd)
. "$kernel_tests/lib.sh" /usr/bin
. "$kernel_tests/gpio_sim_lib.sh"
. "$kernel_tests/lever_sites_lib.sh"
bin=/usr/bin
followers=()

# board_devices: what the rig's guest has at boot, made here by root: vcan0, the gpio-sim and PWM controllers
# (modules built for this kernel, in /lib/modules/RELEASE/extra)
board_devices() {
  modprobe -a irq_sim gpio-sim lever_pwm_sim && ip link add dev vcan0 type vcan && ip link set up vcan0 ||
    { echo "FAILED: the board's simulated devices" >&2; return 1; }
  # udev runs the rule on the new devices; wait until it has handled every event.
  udevadm settle
}

# The levers' configurations (lever_sites_lib's write_config) start from the installed examples, as an admin's do,
# copied before the first is replaced, and are installed where the units read them.
examples=$work/examples
mkdir -p "$examples" && cp /etc/lever/hsi.toml /etc/lever/top.toml "$examples/"
installed_configs=/etc/lever

# journal_lines UNIT CURSOR_FILE: the unit's journal lines (-o cat) from its first in this boot, written as they come.
# It polls with a cursor rather than following: a `journalctl -f -n 0` started just before its unit can miss all of
# its lines without a word; a cursor cannot skip a line, nor miss one written before it started.
# While a scenario runs (quiet_followers ... resume_followers) it starts no journalctl, as the rig's harness starts
# no program then: on this image's voluntary-preemption kernel an ordinary process's system calls can hold the
# loops (docs/deploy.md, "CI's image tests"). The journal keeps the lines; the cursor takes them up.
journal_lines() {
  while :; do
    [[ -e $work/followers-quiet ]] || journalctl -q -u "$1" -o cat --cursor-file="$2"
    sleep 0.2
  done
}
quiet_followers() { : >"$work/followers-quiet"; }
# resume_followers FILE...: the followers poll again, and each FILE (a follower's output) has grown: what the units
# wrote during the scenario is read before the checks that follow (status lines come every second)
resume_followers() {
  local files=("$@") sizes=() i deadline=$((SECONDS + 10))
  size() { stat -c %s "$1" 2>/dev/null || echo 0; }
  for i in "${!files[@]}"; do sizes[i]=$(size "${files[i]}"); done
  rm -f "$work/followers-quiet"
  for i in "${!files[@]}"; do
    while (($(size "${files[i]}") <= sizes[i])); do
      ((SECONDS < deadline)) || { echo "FAILED: ${files[i]} did not grow within 10 s of the followers' resuming" >&2; return 1; }
      sleep 0.2
    done
  done
}

# follow ROLE: the unit's journal, its status lines (JSON) to $out/ROLE.stats, the rest to ROLE.err
follow() {
  # The loop is the background job (its pid is what stop_units kills), awk reads it through a process substitution.
  journal_lines "lever-fw@$1" "$work/$1.cursor" \
    > >(awk -v s="$out/$1.stats" -v e="$out/$1.err" '/^\{/ { print > s; fflush(s); next } { print > e; fflush(e) }') &
  followers+=("$!")
}

# start_fw ROLE: systemctl start lever-fw@ROLE (Type=notify: returns once lever-fw said READY=1); ROLE_pid its
# main process
start_fw() {
  [[ -n ${granted:-} ]] || { udev_grants; granted=1; }
  [[ " ${followed:-} " == *" $1 "* ]] || { follow "$1"; followed+=" $1"; }
  if ! systemctl start "lever-fw@$1"; then
    echo "FAILED: systemctl start lever-fw@$1" >&2
    systemctl status --no-pager "lever-fw@$1" >&2
    return 1
  fi
  printf -v "${1}_pid" '%s' "$(systemctl show -p MainPID --value "lever-fw@$1")"
}

# check_unit_user ROLE: the running lever-fw is the lever user's, with the group gpio, and it did not run as root
check_unit_user() {
  local pid=${1}_pid uid groups
  uid=$(awk '$1 == "Uid:" { print $2 }' "/proc/${!pid:-0}/status" 2>/dev/null)
  groups=$(id -nG lever)
  check "lever-fw@$1 runs as user lever (uid $uid), groups: $groups" \
    test "$uid" = "$(id -u lever)" -a "${groups/gpio/}" != "$groups"
}

# unit_result ROLE: "RESULT EXIT_STATUS" of the unit's last run
unit_result() {
  echo "$(systemctl show -p Result --value "lever-fw@$1") $(systemctl show -p ExecMainStatus --value "lever-fw@$1")"
}

# udev_grants: before any lever-fw runs, the package's udev rule gave group gpio the levers' gpio-sim chips (the
# nodes, 0660) and their PWM chips' export files (writable)
udev_grants() {
  local role gpio node export
  udevadm settle
  for role in hsi top; do
    for gpio in "${role}_encoder_gpio" "${role}_gpio"; do
      node=/dev/$(basename "${!gpio}")
      check "udev: $role's GPIO chip $node is group gpio's, 0660 ($(stat -c '%U:%G %a' "$node"))" \
        test "$(stat -c '%G %a' "$node")" = "gpio 660"
    done
    export=/sys/class/pwm/pwmchip$(pwm_chip $role)/export
    check "udev: $export is group gpio's, writable ($(stat -c '%U:%G %a' "$export"))" \
      test "$(stat -c '%G' "$export")" = gpio -a "$(( $(stat -c '0%a' "$export") & 020 ))" -ne 0
  done
}

stop_units() {
  systemctl stop lever-fw@hsi lever-fw@top 2>/dev/null
  kill "${followers[@]}" 2>/dev/null
  stop_all
}
