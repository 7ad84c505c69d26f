#!/usr/bin/env bash
# lever-fw-sim as a user runs it: help and version, a configuration error, and lever-fw's example configurations
# against the simulated testbed with their status lines.
# usage: lever_fw_sim_cli.sh path/to/lever-fw-sim path/to/firmware/config
set -uo pipefail
fw_sim=$1
examples=$2
source "$(dirname "$0")/lib.sh"

"$fw_sim" --help >"$work/help"; check "--help exits 0" test $? -eq 0
check "--help documents --duration and --fast" grep -q -- "--fast" "$work/help"
"$fw_sim" --version >"$work/version"; check "--version exits 0" test $? -eq 0
check "--version names the program" grep -q "lever-fw-sim" "$work/version"
"$fw_sim" >/dev/null 2>"$work/err"; check "no --config: exit 2" test $? -eq 2
printf '[link]\ncomms_timeout_ms = 0\n' >"$work/bad.toml"
"$fw_sim" --config "$work/bad.toml" >/dev/null 2>"$work/err"; code=$?
check "a configuration error: exit 2 (got $code)" test "$code" -eq 2
check "a configuration error: named as lever-fw names it" grep -qF "link.comms_timeout_ms: must be a whole number" "$work/err"
"$fw_sim" --config "$examples/top.toml" --motor-off >/dev/null 2>&1; code=$?
check "the board's options are not here: --motor-off is bad input, exit 2 (got $code)" test "$code" -eq 2

"$fw_sim" --config "$examples/top.toml" --fast --duration 2 --stats-json >"$work/stats" 2>"$work/err"; code=$?
check "exits 0" test "$code" -eq 0
check "prints a status line a simulated second" test "$(wc -l <"$work/stats")" -ge 3
check "status lines are JSON with the documented fields" \
  jq -e 'has("role") and has("state") and has("faults") and has("position_valid") and has("force_n") and
         has("wakeup_latency_us") and has("step_us") and has("encoder") and has("modbus") and .role == "top"' "$work/stats" >/dev/null
check "the simulated TOP homes and arms" jq -se 'map(.state) | index("armed") != null' "$work/stats" >/dev/null
check "passivity is off by default and sends no energy frames" \
  jq -se 'all(.passivity.mode == "off" and .passivity.energy_sent == 0)' "$work/stats" >/dev/null
sed 's/^mode = "off"/mode = "tdpa"/' "$examples/hsi.toml" >"$work/hsi-tdpa.toml"
"$fw_sim" --config "$work/hsi-tdpa.toml" --fast --duration 3 --stats-json >"$work/stats-tdpa" 2>"$work/err"
check "with control.passivity.mode = tdpa the HSI sends energy frames and reports its energy" \
  jq -se 'last | .passivity.mode == "tdpa" and .passivity.energy_sent > 0 and .passivity.observed_energy_j >= -1e-6
          and .passivity.dissipated_energy_j >= 0' "$work/stats-tdpa" >/dev/null


report "lever-fw-sim cli"
