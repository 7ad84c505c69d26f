#!/usr/bin/env bash
# The README's packet-rate table must be exactly what hil/experiments/rate-table produces from this build.
# usage: readme_rate_table.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
root=$1 build=$2
expected=$(sed -n '/<!-- rate-table:begin -->/,/<!-- rate-table:end -->/p' "$root/README.md" | sed '1d;$d')
actual=$("$root/hil/experiments/rate-table" "$build")
if [[ "$expected" != "$actual" ]]; then
  diff <(echo "$expected") <(echo "$actual") >&2 || true
  echo "README.md's rate table is stale: run hil/experiments/rate-table --update-readme" >&2
  exit 1
fi
echo "README rate table matches hil/experiments/rate-table"
