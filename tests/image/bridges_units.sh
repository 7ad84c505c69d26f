#!/usr/bin/env bash
# Runs on the reference board image (tools/board-image/boot, virtual time): two sites on one board, joined by two
# lever-bridge@ instances started by systemd as user lever-bridge. The HSI's site on vcan0 (lever-bridge@site-a),
# the TOP's on vcan1 (lever-bridge@site-b), UDP on loopback; the key made where docs/deploy.md says
# (/etc/lever/keys/site.key, by lever-bridge keygen, owned by lever-bridge), the configurations from the shipped
# bridge-example.toml, each recording where the unit lets it write (its LogsDirectory, /var/log/lever-bridge). The
# levers under their units as in pair_units.sh; homed and armed from the HSI's site, across the link.
# usage: bridges_units.sh
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/units_lib.sh"
trap 'systemctl stop lever-bridge@site-a lever-bridge@site-b 2>/dev/null; stop_units' EXIT

board_devices || exit 1
ip link add dev vcan1 type vcan && ip link set up vcan1 || exit 1

# As docs/deploy.md ("Configure") has the admin do it.
install -d -m 0750 -g lever-bridge /etc/lever/keys
lever-bridge keygen --out /etc/lever/keys/site.key
chown lever-bridge: /etc/lever/keys/site.key
bridge_config() {  # bridge_config NAME CAN BIND PEER SITE_ID PEER_SITE_ID
  local file=$work/bridge-$1.toml
  cp /etc/lever/bridge-example.toml "$file"
  # The example's keys are top-level (no table): each line replaced where it stands.
  sed -i -e "s|^can = .*|can = \"$2\"|" -e "s|^bind = .*|bind = \"$3\"|" -e "s|^peer = .*|peer = \"$4\"|" "$file"
  printf 'site_id = %s\npeer_site_id = %s\nrecord = "/var/log/lever-bridge/%s.log"\n' "$5" "$6" "$1" >>"$file"
  install -m 0644 "$file" "/etc/lever/bridge-$1.toml"
  echo "/etc/lever/bridge-$1.toml differs from the example in:"
  diff /etc/lever/bridge-example.toml "$file" | sed -n 's/^> /  /p'
}
bridge_config site-a vcan0 127.0.0.1:5000 127.0.0.1:5001 1 2
bridge_config site-b vcan1 127.0.0.1:5001 127.0.0.1:5000 2 1
for site in site-a site-b; do
  journal_lines "lever-bridge@$site" "$work/bridge-$site.cursor" >"$out/bridge-$site.journal" &
  followers+=("$!")
done
# The recording's directory is the unit's LogsDirectory=, made at the first start: --check-config refuses a
# record path in a directory that does not exist yet (seen before the first start), so it is checked after.
require "systemctl start lever-bridge@site-a lever-bridge@site-b" systemctl start lever-bridge@site-a lever-bridge@site-b
for site in site-a site-b; do
  require "lever-bridge --check-config bridge-$site.toml" lever-bridge --config "/etc/lever/bridge-$site.toml" --check-config
  pid=$(systemctl show -p MainPID --value "lever-bridge@$site")
  check "lever-bridge@$site runs as user lever-bridge" test "$(stat -c %U "/proc/$pid")" = lever-bridge
done

lever_chip hsi && lever_chip top && pwm_chips || exit 1
write_config hsi vcan0
write_config top vcan1
candump -r 8388608 -L vcan0 >"$out/two-sites-hsi.candump" &
pids+=("$!")
start_serve two-sites --duration 15 --json || exit 1
start_fw hsi
start_fw top
require "both levers come up disarmed" wait_for 60 hsi '.state == "disarmed"'
require "(TOP too)" wait_for 60 top '.state == "disarmed"'
check "and neither lever's motor guard fired while both started" no_guard_fired hsi top
command vcan0 6
require "home, sent at the HSI's site: the HSI homes" wait_for 120 hsi '.position_valid'
require "and over the link, the TOP homes" wait_for 120 top '.position_valid'
quiet_followers
command vcan0 1
require "arm at the HSI's site: both arm across the bridges (serve saw both armed heartbeats)" \
  wait_for_serve two-sites "both levers armed"
wait "$serve_pid"; code=$?
require "the followers read the journal again" \
  resume_followers "$out/hsi.stats" "$out/top.stats" "$out/bridge-site-a.journal" "$out/bridge-site-b.journal"
check "lever-hil serve ran its 15 s scenario and exited 0 (got $code)" test "$code" -eq 0
r() { jq -r "$1" "$out/two-sites.report"; }
check "both stayed armed through the scenario (armed $(r .armed_s) s)" test "$(r '.armed_s >= 14.5')" = true
check "the TOP holds the HSI's position across the link: rms error $(r .position_rmse) rad < 0.025" \
  test "$(r '.position_rmse < 0.025')" = true

systemctl stop lever-bridge@site-a lever-bridge@site-b
for site in site-a site-b; do
  stats=$(grep '^{' "$out/bridge-$site.journal" | tail -n 1)
  check "lever-bridge@$site relayed frames both ways: $(jq -c '{to: .to_network.frames, from: .from_network.frames}' <<<"$stats")" \
    test "$(jq '.to_network.frames > 1000 and .from_network.frames > 1000' <<<"$stats")" = true
  log=/var/log/lever-bridge/$site.log
  check "its recording $log: $(wc -l <"$log" 2>/dev/null) frames, the user's ($(stat -c '%U %a' "$log" 2>/dev/null))" \
    test "$(wc -l <"$log" 2>/dev/null || echo 0)" -gt 1000 -a "$(stat -c %U "$log" 2>/dev/null)" = lever-bridge
done
cp /var/log/lever-bridge/*.log "$out/" 2>/dev/null
finish "two sites joined by lever-bridge@ units on the board image"
