#!/usr/bin/env bash
# lever-hil as a user runs it: help, argument errors, byte-identical JSON for one seed, sweep outputs.
# usage: lever_hil_cli.sh path/to/lever-hil
set -uo pipefail
hil=$1
source "$(dirname "$0")/lib.sh"
expect_bad() {  # NAME EXPECTED_MESSAGE ARGS...
  local name=$1 expected=$2; shift 2
  "$hil" "$@" >"$work/out" 2>"$work/err"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: says '$expected'" grep -qF -- "$expected" "$work/err"
}

"$hil" --help >"$work/help"; check "--help exits 0" test $? -eq 0
check "--help lists run and sweep" grep -q sweep "$work/help"
"$hil" run --help >"$work/help"; check "run --help exits 0" test $? -eq 0
check "run --help documents --fault" grep -q -- "--fault" "$work/help"

expect_bad "no subcommand" "subcommand"
expect_bad "unknown scenario" "--scenario" run --scenario moonwalk
expect_bad "negative p" "--p" run --p -1
expect_bad "bad fault kind" "unknown kind 'meteor'" run --fault meteor@1
expect_bad "bad fault time" "start 'soon'" run --fault link-down@soon
expect_bad "gauge filter not a number" "--gauge-filter-hz" run --gauge-filter-hz nan
expect_bad "gauge filter out of range" "--gauge-filter-hz" run --gauge-filter-hz 500
expect_bad "gauge rate not the amplifier's" "600 / 2^k" run --gauge-rate-hz 500
expect_bad "gauge noise negative" "--gauge-noise-n" run --gauge-noise-n -0.1
expect_bad "gauge step zero" "--gauge-step-n" run --gauge-step-n 0
"$hil" run --duration 0.5 --gauge-filter-hz 4 --gauge-rate-hz 150 --gauge-noise-n 0.03 --gauge-step-n 0.01 --json >"$work/g.json"
check "the gauge options reach the model" jq -e '.parameters | .gauge_filter_hz == 4 and .gauge_rate_hz == 150 and
  .gauge_noise_n == 0.03 and .gauge_step_n == 0.01' "$work/g.json"
expect_bad "gauge chain unknown" "--gauge-chain" run --gauge-chain bogus
expect_bad "the DAD's settings on the paper's ADC chain" "--gauge-chain dad141" run --topology one-controller \
  --gauge-noise-n 0.01
expect_bad "the HSI's force loop on the paper's chain, where it makes the contact chatter" \
  "makes the contact chatter on the assumed AD620 chain" run --topology one-controller --hsi-force-loop on
expect_bad "a gauge chain for the sphere" "--gauge-chain belongs to the lever scenarios" run --scenario sphere-3dof \
  --gauge-chain paper-adc
expect_bad "the sphere's position sensor for a lever" "--position-sensor belongs to sphere-3dof" run \
  --position-sensor cartesian-grid
"$hil" run --duration 0.5 --topology one-controller --json >"$work/p.json"
check "one controller reads the paper's ADC chain" jq -e '.parameters.gauge_chain == "paper-adc"' "$work/p.json"
"$hil" run --duration 0.5 --topology one-controller --gauge-chain dad141 --gauge-filter-hz 4 --json >"$work/d.json"
check "--gauge-chain dad141 in one controller takes the DAD's settings" \
  jq -e '.parameters | .gauge_chain == "dad141" and .gauge_filter_hz == 4' "$work/d.json"
"$hil" run --scenario sphere-3dof --duration 0.5 --position-sensor cartesian-grid --json >"$work/s.json"
check "--position-sensor reaches the sphere" jq -e '.parameters.position_sensor == "cartesian-grid"' "$work/s.json"
"$hil" run --scenario sphere-3dof --duration 0.5 --position-sensor exact --json >"$work/s.json"
check "--position-sensor exact reaches the sphere" jq -e '.parameters.position_sensor == "exact"' "$work/s.json"
"$hil" run --scenario sphere-3dof --duration 0.5 --seed 2 --json >"$work/s.json"
check "the sphere's TOP keeps its own clock by default, at a phase and drift in range" \
  jq -e '.parameters.top_clock == "own" and .top_clock.phase_ms >= 0 and .top_clock.phase_ms < 1 and
    (.top_clock.drift_ppm | fabs) <= .parameters.top_clock_drift_ppm_max and .top_clock.drift_ppm != 0' "$work/s.json"
"$hil" run --scenario sphere-3dof --duration 0.5 --seed 2 --top-clock op-playout --json >"$work/s.json"
check "--top-clock op-playout reaches the sphere: the OP's clock, no phase, no drift" \
  jq -e '.parameters.top_clock == "op-playout" and .top_clock.phase_ms == 0 and .top_clock.drift_ppm == 0 and
    .top_clock.ticks == 500' "$work/s.json"
expect_bad "a TOP clock unknown" "--top-clock" run --scenario sphere-3dof --top-clock shared
expect_bad "a TOP clock for a lever" "--top-clock belongs to sphere-3dof" run --top-clock own
"$hil" run --scenario sphere-3dof --duration 0.5 --device-encoder-counts 150000 --json >"$work/s.json"
check "--device-encoder-counts reaches the sphere" \
  jq -e '.parameters.device.encoder_counts_per_rev == 150000 and .parameters.position_sensor == "joint-encoders"' \
  "$work/s.json"
"$hil" run --duration 0.5 --operator-speed 2 --operator-dwell 0 --json >"$work/o.json"
check "--operator-speed and --operator-dwell reach the operator" \
  jq -e '.parameters.operator_speed == 2 and .parameters.operator_dwell == 0' "$work/o.json"
expect_bad "operator speed zero" "--operator-speed" run --operator-speed 0
expect_bad "operator dwell negative" "--operator-dwell" run --operator-dwell -1
expect_bad "operator options for the sphere" "--operator-speed and --operator-dwell belong to the lever scenarios" \
  run --scenario sphere-3dof --operator-speed 2
expect_bad "the Omni's encoders too coarse" "--device-encoder-counts" run --scenario sphere-3dof \
  --device-encoder-counts 5
expect_bad "the Omni's encoders for a lever" "--device-encoder-counts belongs to sphere-3dof" run \
  --device-encoder-counts 150000
expect_bad "the Omni's encoders without them" "it needs --position-sensor joint-encoders" run --scenario sphere-3dof \
  --position-sensor exact --device-encoder-counts 150000

args=(run --scenario wall-tap --duration 2 --seed 7 --delay-ms 10 --jitter-ms 3 --loss 0.05 --fault link-down@1+0.2 --json)
"$hil" "${args[@]}" >"$work/a.json"; check "run --json exits 0" test $? -eq 0
"$hil" "${args[@]}" >"$work/b.json"
strip='del(.realtime_factor, .wall_time_s)'
check "same seed, same JSON byte for byte (but timings)" diff <(jq -cS "$strip" "$work/a.json") <(jq -cS "$strip" "$work/b.json")
check "the report has the promised fields" jq -e 'has("velocity_packet_rate") and has("force_packet_rate") and
  has("position_rmse") and has("force_rmse") and has("force_jnd_violation") and has("bus_load") and
  has("realtime_factor") and has("faults") and has("parameters")' "$work/a.json"
check "the fault is reported with the supervisor's reaction" \
  jq -e '.faults[0].kind == "link-down" and (.faults[0].top.fault_at_s >= 1) and (.faults[0].top.safe_at_s != null)' "$work/a.json"
"$hil" run --duration 2 --seed 8 --json | jq -cS "$strip" >"$work/c.json"
check "another seed, another run" bash -c "! diff -q <(jq -cS '$strip' '$work/a.json') '$work/c.json' >/dev/null"

"$hil" run --duration 1 --trace "$work/trace.csv" >/dev/null
check "trace has a header and one row per tick" test "$(wc -l <"$work/trace.csv")" -eq 1001

"$hil" sweep --scenario wall-tap --out "$work/sweep" --seeds 1 --duration 0.5 >"$work/sweep.out" 2>"$work/sweep.err"
check "sweep exits 0" test $? -eq 0
check "sweep printed progress" grep -q "sweep: 63/63 runs" "$work/sweep.err"
for f in sweep.csv summary.csv packet_rate_velocity.png packet_rate_force.png distortion.png position_error.png; do
  check "sweep wrote $f" test -s "$work/sweep/$f"
done
check "summary has 63 points (7 variants x 9 p)" test "$(wc -l <"$work/sweep/summary.csv")" -eq 64

# The delay sweep (issue 14): without passivity (observe) and with tdpa at each delay.
"$hil" sweep --over delay --delays-ms 0,50 --seeds 2 --duration 2 --out "$work/dsweep" >"$work/ds.out" 2>"$work/ds.err"
check "sweep --over delay exits 0" test $? -eq 0
check "sweep --over delay printed progress" grep -q "sweep: 8/8 runs" "$work/ds.err"
for f in sweep.csv summary.csv delay_packet_rates.png delay_force_error.png delay_chatter.png delay_energy.png \
  delay_position.png; do
  check "sweep --over delay wrote $f" test -s "$work/dsweep/$f"
done
check "delay summary: 2 variants x 2 delays" test "$(wc -l <"$work/dsweep/summary.csv")" -eq 5
check "delay runs: 8" test "$(wc -l <"$work/dsweep/sweep.csv")" -eq 9
check "delay summary names its columns" \
  grep -q '^variant,delay_ms,seeds,velocity_rate_percent,.*,contact_onsets_per_s,.*,protection_trips,.*,hsi_dissipated_j,' \
  "$work/dsweep/summary.csv"
# Column 10 is energy frames per second, 16 the JND violation, 28 the HSI's dissipated energy (means).
check "tdpa rows carry energy frames and, at 50 ms, dissipate" \
  awk -F, '$1 == "tdpa" && !($10 > 0) { bad = 1 } $1 == "tdpa" && $2 == 50 && !($28 + $31 > 0) { bad = 1 }
           END { exit bad }' "$work/dsweep/summary.csv"
check "without tdpa nothing is dissipated" \
  awk -F, '$1 == "without" && ($28 != 0 || $31 != 0) { bad = 1 } END { exit bad }' "$work/dsweep/summary.csv"

# sphere-3dof, the paper's 3-DoF experiment: its own report, trace and sweep.
args=(run --scenario sphere-3dof --duration 2 --seed 3 --p-velocity 0 --p-force 0.05 --json)
"$hil" "${args[@]}" >"$work/s1.json"; check "sphere-3dof run --json exits 0" test $? -eq 0
"$hil" "${args[@]}" >"$work/s2.json"
check "sphere-3dof: same seed, same JSON (but timings)" diff <(jq -cS "$strip" "$work/s1.json") <(jq -cS "$strip" "$work/s2.json")
check "sphere-3dof: the report has its fields" jq -e '.scenario == "sphere-3dof" and has("velocity_packet_rate") and
  has("force_packet_rate") and has("contact_share") and has("force_jnd_violation") and has("position_rmse_m") and
  .parameters.force.p == 0.05' "$work/s1.json"
"$hil" run --scenario sphere-3dof --duration 1 --trace "$work/sphere.csv" >/dev/null
check "sphere-3dof trace has a header and one row per tick" test "$(wc -l <"$work/sphere.csv")" -eq 1001
expect_bad "sphere-3dof has no lever faults" "no levers" run --scenario sphere-3dof --fault link-down@1
expect_bad "serve has no sphere-3dof" "no levers" serve --scenario sphere-3dof --hsi-config /dev/null --top-config /dev/null
"$hil" sweep --scenario sphere-3dof --out "$work/sphere-sweep" --seeds 1 --duration 0.2 >/dev/null 2>"$work/sweep.err"
check "sphere-3dof sweep exits 0" test $? -eq 0
for f in sweep.csv summary.csv paper_fig12.csv fig12_packet_rates.png velocity_chains.png distortion.png position_error.png; do
  check "sphere-3dof sweep wrote $f" test -s "$work/sphere-sweep/$f"
done
check "sphere-3dof summary has 180 points (velocity: 4 chains, force: 1; 3 modes x 12 p)" \
  test "$(wc -l <"$work/sphere-sweep/summary.csv")" -eq 181

# serve, on a machine without the levers' devices: bad configurations are bad input, missing devices a
# runtime failure naming the device; the end-to-end runs are in tests/kernel/lever_*.sh.
printf '[lever]\nrole = "hsi"\n' >"$work/hsi.toml"
printf '[lever]\nrole = "top"\n' >"$work/top.toml"
printf '[lever]\nrole = "top"\npair = 3\n' >"$work/top3.toml"
printf '[lever]\nrole = "hsi"\nspeed = 1\n' >"$work/bad.toml"
"$hil" serve --help >"$work/help"; check "serve --help exits 0" test $? -eq 0
check "serve --help names the configs" grep -q -- "--hsi-config" "$work/help"
expect_bad "serve: two HSI configs" "must configure an HSI lever" serve --hsi-config "$work/hsi.toml" --top-config "$work/hsi.toml"
expect_bad "serve: levers of different pairs" "different pairs" serve --hsi-config "$work/hsi.toml" --top-config "$work/top3.toml"
expect_bad "serve: a config error names file and key" "lever.speed: unknown key" serve --hsi-config "$work/bad.toml" --top-config "$work/top.toml"
expect_bad "serve: a missing config" "--hsi-config" serve --hsi-config "$work/none.toml" --top-config "$work/top.toml"
printf '[lever]\nrole = "hsi"\n[board.encoder]\nchip = "/dev/no-such-chip"\n' >"$work/nochip.toml"
timeout 20 "$hil" serve --hsi-config "$work/nochip.toml" --top-config "$work/top.toml" 2>"$work/err"; code=$?
check "serve without the encoder's chip: exit 1 (got $code)" test "$code" -eq 1
check "and names the lever, the encoder and the chip" grep -q "HSI encoder.*no-such-chip" "$work/err"

report "lever-hil cli"
