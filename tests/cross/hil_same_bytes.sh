#!/usr/bin/env bash
# The HIL means the same run on every architecture: short lever-hil scenarios (wall-tap with faults and the
# prefilter, tdpa under delay and jitter with the predictive codec, the sphere through its driver's Butterworth,
# Fig. 8's chain: one controller, the DAD 141.1 gauge chain, the HSI's force loop, the adaptive window) run natively
# and, under qemu-user, as built for each Arm architecture given, must give byte-identical JSON reports and per-tick
# traces. The reports' two wall-clock fields (wall_time_s, realtime_factor) are the only ones taken out.
# usage: hil_same_bytes.sh SOURCE_DIR NATIVE_LEVER_HIL ARCH=LEVER_HIL...
set -uo pipefail
source=$1 native=$2
shift 2
source "$(dirname "$0")/../cli/lib.sh"

scenarios=(
  "wall-tap-faults run --scenario wall-tap --duration 6 --seed 7 --filter-hz 40 --fault link-down@2+0.3
   --fault reboot@3+0.2:hsi --fault encoder-glitch@4.5+0.01:top --fault gauge-stale@5+0.2"
  "tdpa-delay run --scenario wall-tap --duration 5 --seed 3 --mode predictive --passivity tdpa --delay-ms 25
   --jitter-ms 2 --loss 0.01"
  "sphere run --scenario sphere-3dof --duration 4 --seed 2 --p 0.05"
  "paper-chain run --scenario wall-tap --duration 4 --seed 5 --topology one-controller --gauge-chain dad141
   --hsi-force-loop on --motion-velocity adaptive-window --p 0.1"
)
# One run: the report without its wall-clock fields, and the trace.
run() {
  local out=$1 name=$2
  shift 2
  "$@" --json --trace "$out/$name.csv" >"$out/$name.raw.json" &&
    sed -E 's/"(wall_time_s|realtime_factor)":[-+0-9.eE]+,?//g; s/,}/}/g' "$out/$name.raw.json" >"$out/$name.json" &&
    ! grep -qE 'wall_time_s|realtime_factor' "$out/$name.json"
}

mkdir -p "$work/amd64"
for scenario in "${scenarios[@]}"; do
  read -r -a words <<<"$scenario"
  check "amd64: ${words[0]} runs" run "$work/amd64" "${words[0]}" "$native" "${words[@]:1}"
done
for target in "$@"; do
  arch=${target%%=*} program=${target#*=}
  case $arch in
    arm64) qemu=qemu-aarch64-static ;;
    armhf) qemu=qemu-arm-static ;;
    *) echo "hil_same_bytes: unknown architecture $arch" >&2; exit 2 ;;
  esac
  sysroot=$("$source/scripts/sysroot" "$arch") || { check "$arch: its sysroot" false; continue; }
  mkdir -p "$work/$arch"
  for scenario in "${scenarios[@]}"; do
    read -r -a words <<<"$scenario"
    name=${words[0]}
    start=$SECONDS
    check "$arch: $name runs under $qemu" run "$work/$arch" "$name" "$qemu" -L "$sysroot" "$program" "${words[@]:1}"
    for file in "$name.json" "$name.csv"; do
      check "$arch: $file is amd64's, byte for byte ($(cmp "$work/amd64/$file" "$work/$arch/$file" 2>&1 | head -1))" \
        cmp -s "$work/amd64/$file" "$work/$arch/$file"
    done
    echo "$arch $name: $(wc -l <"$work/$arch/$name.csv") trace lines, $(wc -c <"$work/$arch/$name.json") bytes of report, in $((SECONDS - start)) s under qemu"
  done
done
report "hil same bytes"
