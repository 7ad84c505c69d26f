#!/usr/bin/env bash
# Every example command in README.md and docs/*.md, run as written with the built programs: each must exit 0,
# and a documented output line ("# {...}" under a command) must match what the command prints. A synopsis
# (placeholders: [OPTIONAL], a|b, FILE) is no command; the other lines that cannot run here are listed below
# with the reason. Any other line is run, so a new example is checked the day it is written.
# usage: doc_examples.sh SOURCE_DIR BIN_DIR
set -uo pipefail
src=$(realpath "$1") bin=$(realpath "$2")
source "$(dirname "$0")/lib.sh"

# Exact lines that are examples but cannot run in a test, and why.
declare -A skip=(
  ["lever-bridge --can can0 --bind 0.0.0.0:5000 --peer 192.0.2.7:5000 --key site.key --site-id 1 --peer-site-id 2 --record site-a.log --stats-json"]="needs a CAN interface can0 and a peer at 192.0.2.7 (tests/kernel runs the bridge on a kernel CAN stack)"
  ["lever-bridge --config bridge.toml --check-config                # validate the file and the key; open nothing"]="needs the reader's bridge.toml (tests/cli/lever_bridge_cli.sh checks --check-config on its own files)"
  ["lever-bridge --config bridge.toml                               # the same options from a file"]="needs a bridge.toml naming a CAN interface (tests/kernel)"
  ["lever-plot one-site.candump --status hsi.stats --status top.stats --out plots   # a session of pair 0"]="needs a recording (tests/cli/lever_plot_cli.sh runs it on lever_one_site's, tests/cli/one-site-session.tar.xz)"
  ["lever-study run --can can0 --pair 0 --protocol 3ifc --subject s01 --log s01-3ifc.jsonl --progress /dev/pts/3"]="needs a pair on can0 and a subject at this terminal (tests/kernel/lever_study.sh runs a whole session on the rig's pair)"
  ["lever-study run --can can0 --protocol rating --subject s01 --log s01-rating.jsonl --progress progress.txt"]="needs a pair on can0 and a subject at this terminal (tests/kernel/lever_study.sh)"
  ["lever-fw --config top.toml --stats-json"]="runs the board's hardware (the e2e tests in tests/kernel run this command on gpio-sim, with a top.toml from the example)"
)

# Each document's examples run in order in a directory of their own, with the programs on PATH and under
# build/bin as the docs call them, the example configurations where the README names them, and a top.toml of
# the reader's own (bring-up.md) as the example one.
setup() {
  mkdir -p "$1/build" "$1/firmware"
  ln -s "$bin" "$1/build/bin"
  cp -r "$src/firmware/config" "$1/firmware/config"
  cp "$src/firmware/config/top.toml" "$src/firmware/config/hsi.toml" "$1/"
}
export PATH="$bin:$PATH"

is_synopsis() { [[ $1 =~ \[|[a-z0-9]\|[a-z-]|\ \|\ -|\ [A-Z][A-Z_]*([\ :]|$) ]]; }

examples=0 ran=0 skipped=0
for doc in "$src/README.md" "$src"/docs/*.md; do
  name=${doc#"$src/"}
  in_block=0 last_output="" pending=""
  dir="$work/run/$(basename "$doc" .md)"
  setup "$dir"
  while IFS= read -r line; do
    # A command continued with a backslash is one command.
    if [ "$in_block" = 1 ] && [[ $line == *\\ ]]; then pending+="${line%\\}"; continue; fi
    if [ -n "$pending" ]; then line="${pending% } ${line#"${line%%[! ]*}"}"; pending=""; fi
    if [[ $line == '```'* ]]; then in_block=$((1 - in_block)); continue; fi
    [ "$in_block" = 1 ] || continue
    # A documented output under the last command: its numbers must be what the command printed.
    if [[ $line == '# {'* && -n $last_output ]]; then
      while IFS= read -r pair; do
        key=${pair%%:*} value=${pair#*:}
        if [[ $value == *... ]]; then
          check "$name: documented $key ${value} is what the example prints ($(grep -o "$key:[^,}]*" <<<"$last_output"))" \
            grep -qF -- "$key:${value%...}" <<<"$last_output"
        else
          check "$name: documented $key $value is what the example prints ($(grep -o "$key:[^,}]*" <<<"$last_output"))" \
            grep -qE -- "$key:$value[,}]" <<<"$last_output"
        fi
      done < <(grep -oE '"[a-z_]+":[-0-9.e+]+(\.\.\.)?' <<<"${line#\# }")
      continue
    fi
    [[ $line =~ ^(build/bin/)?lever-(codec|hil|fw|fw-sim|bridge|plot|study)\  ]] || continue
    examples=$((examples + 1))
    if is_synopsis "${line%%#*}"; then skipped=$((skipped + 1)); continue; fi
    if [ -n "${skip[$line]+x}" ]; then
      echo "skipped ($name): $line -- ${skip[$line]}"
      skipped=$((skipped + 1))
      continue
    fi
    ran=$((ran + 1))
    last_output=$(cd "$dir" && timeout 120 bash -c "$line" 2>"$work/err")
    code=$?
    check "$name: '$line' exits 0 (got $code: $(head -c 300 "$work/err"))" test "$code" -eq 0
  done <"$doc"
done
echo "examples: $examples, run: $ran, skipped: $skipped (synopses and the list above)"
check "examples were found and run" test "$ran" -ge 5
report "doc examples"
