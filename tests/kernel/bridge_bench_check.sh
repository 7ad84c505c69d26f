#!/usr/bin/env bash
# Runs scripts/bench-bridge with few frames (the build given as its own "old" build, so that every variant runs)
# and checks only that its JSON is well-formed and complete: every variant, every figure a number, every frame
# sent accounted for. No figure is compared with anything: timing belongs to the benchmark, not to a test.
# usage: bridge_bench_check.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
root=$1 build=$2
json=$(mktemp)
trap 'rm -f "$json"' EXIT
"$root/scripts/bench-bridge" --frames 40 --rounds 2 --old "$build" --out "$json" "$build" >/dev/null || {
  echo "bench-bridge failed" >&2
  exit 1
}
expected='["cangw", "new", "new-norec", "new-rt0", "old", "old-norec"]'
[[ -x $build/bin/lever-bench-relay-floor ]] &&
  expected='["cangw", "new", "new-norec", "new-rt0", "floor", "floor-hmac", "old", "old-norec"]'
jq -e --argjson expected "$expected" '
  def num: type == "number" and (isnan | not) and (isinfinite | not);
  (.variants | keys | sort) == ($expected | sort)
  and ([.variants[] | (.frames + .lost) == 40 and .frames > 0
        and (.p50_us | num) and (.p99_us | num) and (.p99_9_us | num) and (.max_us | num)
        and (.ratio_to_cangw | (.p50 | num) and (.p99 | num) and (.p99_9 | num))] | all)
  and (.frames_per_variant == 40) and (.rounds == 2)' "$json" >/dev/null || {
  echo "bench-bridge's JSON is incomplete:" >&2
  cat "$json" >&2
  exit 1
}
echo "bench-bridge: JSON well-formed and complete ($(jq -c '[.variants | to_entries[] | "\(.key): \(.value.frames)"]' "$json"))"
