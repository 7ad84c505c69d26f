#!/usr/bin/env bash
# The demo on a fresh Debian 12: a minimal root (mmdebstrap --variant=minbase, from the mirror this machine's apt
# uses), this tree's committed HEAD copied in, and `./scripts/demo` timed inside it as a new user runs it, as root:
# its packages installed by scripts/setup --demo, its programs built without ccache, the demo run. Not in ctest: it
# downloads about 130 MB and takes minutes; the time it prints is the one README.md's quick start gives.
# usage: tests/demo/fresh_machine.sh WORK_DIR   (as root; WORK_DIR must not exist; it is left for inspection)
set -euo pipefail
case ${1:-} in
  -h | --help) sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  "" | -*) echo "fresh_machine.sh: needs a WORK_DIR that does not exist (see --help)" >&2; exit 2 ;;
esac
work=$1
[[ ! -e $work ]] || { echo "fresh_machine.sh: $work exists" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
mirror=$(awk '/^URIs:/ { print $2; exit }' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
mirror=${mirror:-http://deb.debian.org/debian}
mkdir -p "$work/root"
mmdebstrap --variant=minbase bookworm "$work/root" "deb $mirror bookworm main" \
  "deb $mirror bookworm-updates main" "deb ${mirror%/debian}/debian-security bookworm-security main"
cp /etc/resolv.conf "$work/root/etc/resolv.conf"
mkdir "$work/root/src"
git -C "$root" archive HEAD | tar -C "$work/root/src" -x
for fs in proc dev sys; do mount --bind "/$fs" "$work/root/$fs"; done
trap 'for fs in proc dev sys; do umount "$work/root/$fs"; done' EXIT
start=$(date +%s.%N)
chroot "$work/root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root \
  bash -c 'cd /src && ./scripts/demo' >"$work/demo.log" 2>&1
end=$(date +%s.%N)
printf 'fresh_machine.sh: ./scripts/demo took %.0f s on a fresh Debian 12 root (log: %s)\n' \
  "$(echo "$end - $start" | bc)" "$work/demo.log"
