#!/usr/bin/env bash
# Runs inside the kernel rig (scripts/bench-bridge starts it): the bridge's latency beside the kernel's own CAN
# gateway, in one guest boot. Interleaved blocks, each a variant relaying vcan0 -> vcan1:
#   cangw              the in-kernel can-gw (cangw -A -s vcan0 -d vcan1 -e), the floor;
#   new, new-norec     BIN_DIR's lever-bridge pair (vcan0 -> UDP loopback -> vcan1), recorder on and off;
#   new-rt0            the same, recorder on, --realtime-priority 0 (what real time buys);
#   old, old-norec     OLD_BIN_DIR's lever-bridge pair, when given, as it runs by default;
#   floor              BIN_DIR's lever-bench-relay-floor pair: the same hops (vcan0 -> UDP loopback -> vcan1, two
#                      processes, SCHED_FIFO 40) with nothing else, the floor of any such user-space relay;
#   floor-hmac         the same with the bridge's datagram encoded and verified (precomputed HMAC state).
# The floor variants are in the default set when BIN_DIR has lever-bench-relay-floor (a build with benchmarks).
# cangen sends each block's frames at 1 kHz with a block's own id; candump -L logs both interfaces with the
# kernel's receive stamps, so the latency of a frame is its stamp on vcan1 minus its stamp on vcan0, whatever the
# observers' scheduling. Prints one JSON document: per variant the frames, p50, p99, p99.9 (us) and their ratios
# to cangw's. A benchmark, not a test: it asserts nothing about the figures.
# usage: bridge_bench.sh BIN_DIR [OLD_BIN_DIR]
# environment: BENCH_FRAMES (per variant, default 2000), BENCH_ROUNDS (blocks per variant, default 4),
#              BENCH_LOAD (busy loops in the guest beside the relay, default 0), BENCH_RATE_GAP_MS (default 1),
#              BENCH_VARIANTS (a comma-separated subset of the variants besides cangw; default all)
set -uo pipefail
. "$(dirname "$0")/lib.sh"
old_bin=${2:-}
frames=${BENCH_FRAMES:-2000}
rounds=${BENCH_ROUNDS:-4}
load=${BENCH_LOAD:-0}
gap_ms=${BENCH_RATE_GAP_MS:-1}
per_block=$(((frames + rounds - 1) / rounds))
python=/usr/bin/python3

variants=(cangw new new-norec new-rt0)
[[ -x $bin/lever-bench-relay-floor ]] && variants+=(floor floor-hmac)
[[ -n $old_bin ]] && variants+=(old old-norec)
# BENCH_VARIANTS: a subset, for a quicker look (cangw is always measured: the ratios need it).
if [[ -n ${BENCH_VARIANTS:-} ]]; then
  read -ra variants <<<"cangw ${BENCH_VARIANTS//,/ }"
fi

busy=()
for ((i = 0; i < load; i++)); do
  bash -c 'while :; do :; done' &
  busy+=($!)
done

candump -r 8388608 -L vcan0 >"$work/vcan0.log" &
dump0=$!
candump -r 8388608 -L vcan1 >"$work/vcan1.log" &
dump1=$!
sleep 0.5

start_pair() {  # start_pair BIN rec|norec EXTRA_ARGS...: a bridge on each interface, joined over loopback
  local dir=$1 record=$2; shift 2
  local rec_a=() rec_b=()
  if [[ $record == rec ]]; then rec_a=(--record "$work/rec-$block-a.log") rec_b=(--record "$work/rec-$block-b.log"); fi
  "$dir/lever-bridge" --can vcan0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key" --site-id 1 \
    "${rec_a[@]}" "$@" >/dev/null 2>>"$work/bridges.err" &
  pair_a=$!
  "$dir/lever-bridge" --can vcan1 --bind 127.0.0.1:5001 --peer 127.0.0.1:5000 --key "$key" --site-id 2 \
    "${rec_b[@]}" "$@" >/dev/null 2>>"$work/bridges.err" &
  pair_b=$!
  # The first probe exchange (within 50 ms of the start) teaches both ends each other's epoch; frames sent before
  # it are dropped as stale, so none is sent until well after.
  sleep 1
}
start_floor() {  # start_floor EXTRA_ARGS...: the floor relay's two processes, the receiver first
  "$bin/lever-bench-relay-floor" udp-to-can --bind 127.0.0.1:5001 --can vcan1 "$@" 2>>"$work/bridges.err" &
  pair_b=$!
  "$bin/lever-bench-relay-floor" can-to-udp --can vcan0 --peer 127.0.0.1:5001 "$@" 2>>"$work/bridges.err" &
  pair_a=$!
  sleep 1  # as long as the bridges get
}
stop_pair() { kill -TERM $pair_a $pair_b; wait $pair_a $pair_b 2>/dev/null; }

: >"$work/blocks"
block=0
for ((round = 0; round < rounds; round++)); do
  for variant in "${variants[@]}"; do
    id=$(printf '%03X' $((0x100 + block)))  # within the default allow-list (0x100-0x15F)
    case $variant in
      cangw) cangw -A -s vcan0 -d vcan1 -e ;;  # -e: frames sent on this host (cangen) count too
      new) start_pair "$bin" rec ;;
      new-norec) start_pair "$bin" norec ;;
      new-rt0) start_pair "$bin" rec --realtime-priority 0 ;;
      old) start_pair "$old_bin" rec ;;
      old-norec) start_pair "$old_bin" norec ;;
      floor) start_floor ;;
      floor-hmac) start_floor --hmac ;;
    esac
    cangen vcan0 -I "$id" -L 8 -D i -g "$gap_ms" -n "$per_block"
    sleep 0.3
    if [[ $variant == cangw ]]; then cangw -F; else stop_pair; fi
    echo "$id $variant" >>"$work/blocks"
    block=$((block + 1))
  done
done
sleep 0.3
kill $dump0 $dump1
wait $dump0 $dump1 2>/dev/null
((${#busy[@]})) && kill "${busy[@]}" && wait "${busy[@]}" 2>/dev/null

"$python" - "$work/blocks" "$work/vcan0.log" "$work/vcan1.log" "$frames" "$rounds" "$per_block" "$load" \
  "$gap_ms" <<'EOF' | tee "$out/bridge_bench.json"
import json, math, sys
from collections import defaultdict

blocks_file, log0, log1, frames, rounds, per_block, load, gap_ms = sys.argv[1:9]
variant_of = dict(line.split() for line in open(blocks_file))

def read(path):
    # (sec.usec) iface ID#DATA -> {(id, data, n-th of its kind): stamp in us}
    seen, out = defaultdict(int), {}
    for line in open(path):
        stamp, _, frame = line.split()
        ident, data = frame.split("#")
        if ident not in variant_of:
            continue
        key = (ident, data, seen[(ident, data)])
        seen[(ident, data)] += 1
        sec, usec = stamp.strip("()").split(".")
        out[key] = int(sec) * 1_000_000 + int(usec)
    return out

sent, received = read(log0), read(log1)
latencies, lost = defaultdict(list), defaultdict(int)
for key, t0 in sent.items():
    variant = variant_of[key[0]]
    if key in received:
        latencies[variant].append(received[key] - t0)
    else:
        lost[variant] += 1

def percentile(values, q):  # nearest rank
    ordered = sorted(values)
    return ordered[max(0, math.ceil(q * len(ordered)) - 1)] if ordered else None

figures = {}
for variant in dict.fromkeys(variant_of.values()):
    values = latencies[variant]
    figures[variant] = {
        "frames": len(values),
        "lost": lost[variant],
        "p50_us": percentile(values, 0.50),
        "p99_us": percentile(values, 0.99),
        "p99_9_us": percentile(values, 0.999),
        "max_us": max(values) if values else None,
    }
floor = figures.get("cangw", {})
for variant, f in figures.items():
    f["ratio_to_cangw"] = {
        q: (round(f[q + "_us"] / floor[q + "_us"], 2) if f[q + "_us"] and floor.get(q + "_us") else None)
        for q in ("p50", "p99", "p99_9")
    }
with open("/proc/loadavg") as guest_load:
    guest_loadavg = guest_load.read().split()[:3]
print(json.dumps({
    "method": "vcan0 -> vcan1, candump -L kernel stamps on both; cangen at 1 frame per gap; blocks of each variant "
              "interleaved round by round in one guest boot (Debian's kernel under QEMU TCG, one vCPU)",
    "frames_per_variant": int(frames), "rounds": int(rounds), "frames_per_block": int(per_block),
    "gap_ms": float(gap_ms), "busy_loops_in_guest": int(load), "guest_loadavg_at_end": guest_loadavg,
    "variants": figures,
}, indent=2))
EOF
status=${PIPESTATUS[0]}
if [[ -s $work/bridges.err ]] && grep -q 'WARNING\|error' "$work/bridges.err"; then
  echo "bridge_bench: the bridges said:" >&2
  grep 'WARNING\|error' "$work/bridges.err" | sort | uniq -c >&2
fi
exit "$status"
