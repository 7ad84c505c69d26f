#!/usr/bin/env bash
# The include check must fail on a forbidden include: a tree with every room, where lever-fw includes the HIL,
# the HIL's library includes lever::app, and the study library and the HIL's library include each other (the
# directions docs/architecture.md forbids), must be refused with each named; the same tree without them must pass,
# lever-hil's study subcommand including lever::study among its allowed includes.
# usage: check_includes_rejects.sh path/to/check_includes.sh
set -uo pipefail
check=$1
source "$(dirname "$0")/../cli/lib.sh"
for room in program common codec_cli firmware/core firmware/mcu board firmware/app host/codec_tool host/bridge host/ctl host/view host/plot host/study \
  hil/devices hil/include hil/src hil/app hil/fw-sim; do
  mkdir -p "$work/tree/$room"
done
printf '#include "lever/app/fw_config.hpp"\n#include "lever/board/result.hpp"\n' >"$work/tree/firmware/app/main.cpp"
printf '#include "lever/hil/simulation.hpp"\n#include "lever/app/stats_line.hpp"\n' >"$work/tree/hil/fw-sim/main.cpp"
printf '#include "lever/hil/hosted_rig.hpp"\n#include "lever/study/pair_watch.hpp"\n' >"$work/tree/hil/app/study.cpp"
"$check" "$work/tree" >"$work/out"; code=$?
check "allowed includes pass: exit 0 (got $code: $(cat "$work/out"))" test "$code" -eq 0

printf '#include "lever/hil/simulation.hpp"\n' >>"$work/tree/firmware/app/main.cpp"
printf '  #  include "lever/app/fw_config.hpp"\n' >"$work/tree/hil/src/world.cpp"
printf '#include "lever/study/session_log.hpp"\n' >"$work/tree/hil/src/hosted_rig.cpp"
printf '#include "lever/hil/hosted_rig.hpp"\n' >"$work/tree/host/study/main.cpp"
"$check" "$work/tree" >"$work/out"; code=$?
check "forbidden includes: exit 1 (got $code)" test "$code" -eq 1
check "lever-fw including the HIL is named with file and line" \
  grep -qF "firmware/app/main.cpp:3: firmware/app may not include lever/hil/simulation.hpp" "$work/out"
check "the HIL's library including lever::app is named" \
  grep -qF "hil/src/world.cpp:1: hil/src may not include lever/app/fw_config.hpp" "$work/out"
check "the HIL's library including the study library is named" \
  grep -qF "hil/src/hosted_rig.cpp:1: hil/src may not include lever/study/session_log.hpp" "$work/out"
check "lever-study including the HIL is named" \
  grep -qF "host/study/main.cpp:1: host/study may not include lever/hil/hosted_rig.hpp" "$work/out"
rm -r "$work/tree/hil/app"
"$check" "$work/tree" >/dev/null 2>"$work/err"; code=$?
check "a room that is gone fails the check: exit 1 (got $code)" test "$code" -eq 1
report "include check rejects"
