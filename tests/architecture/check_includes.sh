#!/usr/bin/env bash
# Who may include whom (docs/architecture.md, "Rooms"): every '#include "lever/..."' in a room's sources must name a
# room that room may include; anything else is named with its file and line, and the check fails. Rooms are
# folders; an include names its room by its path (lever/fw/... is firmware/core, lever/hil/devices/... is
# hil/devices). tests/, bench/ and fuzz/ may include anything and are not checked.
# usage: check_includes.sh SOURCE_DIR      exit 0: every include allowed; 1: some are not; 2: bad usage
set -uo pipefail
[[ $# -eq 1 && -d $1 ]] || { echo "usage: check_includes.sh SOURCE_DIR" >&2; exit 2; }
cd "$1" || exit 2

# folder (the room) | the rooms it may include, by their include names; each may include itself
rules=(
  "program|program"
  "common|codec common math protocol"
  "codec_cli|codec common math protocol program codec_cli"
  "firmware/core|codec common math protocol fw"
  "firmware/mcu|codec common math protocol fw"
  "board|codec common math protocol fw board"
  "firmware/app|codec common math protocol fw board program codec_cli app"
  "host/codec_tool|codec common math protocol program codec_cli"
  "host/bridge|codec common math protocol board program"
  "host/ctl|codec common math protocol board program codec_cli"
  "host/view|codec common math protocol board program"
  "host/plot|codec common math protocol program"
  "host/study|codec common math protocol board program study"
  "hil/devices|codec common math protocol fw board hil/devices"
  "hil/include|codec common math protocol fw hil"
  "hil/src|codec common math protocol fw hil"
  "hil/app|codec common math protocol fw board program codec_cli app hil hil/devices study"
  "hil/fw-sim|codec common math protocol fw program app hil"
)

bad=0 files=0
for rule in "${rules[@]}"; do
  room=${rule%%|*}
  allowed=" ${rule#*|} "
  [[ -d $room ]] || { echo "check_includes: room $room does not exist: update the rules and docs/architecture.md" >&2; bad=1; continue; }
  while IFS= read -r file; do
    files=$((files + 1))
    while IFS=: read -r line include; do
      name=${include#lever/}
      [[ $name == hil/devices/* ]] && key=hil/devices || key=${name%%/*}
      if [[ $allowed != *" $key "* ]]; then
        echo "check_includes: $file:$line: $room may not include $include (it may include:${allowed% })"
        bad=1
      fi
    done < <(grep -no '^[[:space:]]*#[[:space:]]*include[[:space:]]*"lever/[^"]*"' "$file" | sed -E 's/:[^"]*"/:/; s/"$//')
  done < <(find "$room" -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) | sort)
done
((bad == 0)) && echo "check_includes: $files files in ${#rules[@]} rooms include only the rooms they may"
exit "$bad"
