#!/usr/bin/env bash
# scripts/demo in its short mode: every figure of its two tables (Fig. 8 and Fig. 12 beside the paper) must be the
# CSV's, found here by the column's name: the printed figure is the summary's mean (or the sum of two: the link's
# refresh and rest-repeat frames), the summary's mean is the mean of the runs in sweep.csv, and sweep.csv's run
# for seed 1 is what `lever-hil run` reports for the same point. Its simulated study session's summary is labelled
# simulated and is what lever-study reports from the log the demo wrote.
# usage: demo_tables.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
root=$1 build=$2
source "$root/tests/cli/lib.sh"
hil=$build/bin/lever-hil

"$root/scripts/demo" --short --build "$build" --out "$work/demo" >"$work/out" 2>"$work/err"
code=$?
check "the demo exits 0 (got $code; $(tail -1 "$work/err"))" test "$code" -eq 0

# column CSV NAME: NAME's column number in the CSV's header (empty if absent).
column() { head -1 "$1" | tr -d '\r' | tr ',' '\n' | grep -nxF -- "$2" | cut -d: -f1; }
# where CSV "NAME=VALUE;...": the key columns' numbers and values, "NUMBER=VALUE;...", for matching below.
where() {
  local csv=$1 kv k spec=""
  local -a keys
  IFS=';' read -ra keys <<<"$2"
  for kv in "${keys[@]}"; do
    k=$(column "$csv" "${kv%%=*}")
    [[ -n $k ]] || { echo "no column ${kv%%=*} in $csv" >&2; return 1; }
    spec+="$k=${kv#*=};"
  done
  echo "$spec"
}
# matching CSV COLUMN_NAME "KEY=VALUE;...": the named column of every row whose keys hold those values (numbers
# compared as numbers); fails if a name is not in the header or no row matches.
matching() {
  local csv=$1 name=$2 c spec
  c=$(column "$csv" "$name")
  [[ -n $c ]] || { echo "no column $name in $csv" >&2; return 1; }
  spec=$(where "$csv" "$3") || return 1
  awk -F, -v c="$c" -v spec="$spec" 'NR > 1 {
      n = split(spec, s, ";"); ok = 1
      for (i = 1; i < n; i++) { split(s[i], p, "="); v = $p[1]
        if (v != p[2] && !(v ~ /^[-+.0-9eE]+$/ && (v - p[2]) ^ 2 < 1e-18)) ok = 0 }
      if (ok) { print $c; found = 1 } }
    END { exit !found }' "$csv"
}
# cell CSV COLUMN_NAME KEYS: the first matching row's; runs_mean CSV COLUMN_NAME KEYS: the mean of all, times 100.
cell() { matching "$@" | head -1; }
runs_mean() { matching "$@" | awk '{ sum += $1 } END { if (!NR) exit 1; printf "%.6f", 100 * sum / NR }'; }
one_decimal() { awk -v x="$1" 'BEGIN { printf "%.1f", x }'; }
near() { awk -v a="$1" -v b="$2" -v d="$3" 'BEGIN { exit !((a - b) ^ 2 <= d ^ 2) }'; }

# check_figure LABEL PRINTED SUMMARY SWEEP SUMMARY_COLUMN RUN_COLUMN SUMMARY_KEYS RUN_KEYS
check_figure() {
  local label=$1 printed=$2 summary=$3 sweep=$4 scol=$5 rcol=$6 skeys=$7 rkeys=$8 mean runs
  mean=$(cell "$summary" "$scol" "$skeys")
  check "$label: the summary has a row and a $scol column" test -n "$mean"
  check "$label: printed $printed is the summary's $scol $mean" test "$printed" = "$(one_decimal "${mean:-nan}")"
  runs=$(runs_mean "$sweep" "$rcol" "$rkeys")
  check "$label: the summary's $scol $mean is the mean of sweep.csv's $rcol ($runs)" near "${mean:-0}" "${runs:-1e9}" 0.0051
}

# check_link_frames LABEL PRINTED SUMMARY SWEEP DIRECTION SUMMARY_KEYS RUN_KEYS: the link's own frames, printed as
# the sum of the summary's refresh and rest-repeat means, each the mean of its runs in sweep.csv.
check_link_frames() {
  local label=$1 printed=$2 summary=$3 sweep=$4 dir=$5 skeys=$6 rkeys=$7 a b ra rb
  a=$(cell "$summary" "${dir}_refresh_percent" "$skeys")
  b=$(cell "$summary" "${dir}_rest_repeat_percent" "$skeys")
  check "$label: printed $printed is the summary's refresh $a + rest repeat $b" \
    test "$printed" = "$(one_decimal "$(awk -v a="${a:-nan}" -v b="${b:-nan}" 'BEGIN { print a + b }')")"
  ra=$(runs_mean "$sweep" "${dir}_refresh_rate" "$rkeys")
  rb=$(runs_mean "$sweep" "${dir}_rest_repeat_rate" "$rkeys")
  check "$label: the summary's refresh $a is the mean of sweep.csv's ($ra)" near "${a:-0}" "${ra:-1e9}" 0.0051
  check "$label: the summary's rest repeat $b is the mean of sweep.csv's ($rb)" near "${b:-0}" "${rb:-1e9}" 0.0051
}

# The Fig. 8 table: "  VARIANT p=P %[, ...]   VELOCITY % + LINK %   FORCE % + LINK %   OFF-JND %   [paper]".
sweep_dir=$work/demo/sweep
rows=0
while read -r variant p v vl f fl j; do
  rows=$((rows + 1))
  pr=$(awk -v p="$p" 'BEGIN { print p / 100 }')
  for m in "velocity $v velocity_deadband_percent velocity_deadband_rate" \
    "force $f force_deadband_percent force_deadband_rate" "off-JND $j jnd_violation_percent force_jnd_violation"; do
    read -r what printed scol rcol <<<"$m"
    check_figure "Fig. 8, $variant p=$p %, $what" "$printed" "$sweep_dir/summary.csv" "$sweep_dir/sweep.csv" \
      "$scol" "$rcol" "variant=$variant;p_percent=$p" "variant=$variant;p=$pr"
  done
  check_link_frames "Fig. 8, $variant p=$p %, velocity's link frames" "$vl" "$sweep_dir/summary.csv" \
    "$sweep_dir/sweep.csv" velocity "variant=$variant;p_percent=$p" "variant=$variant;p=$pr"
  check_link_frames "Fig. 8, $variant p=$p %, force's link frames" "$fl" "$sweep_dir/summary.csv" \
    "$sweep_dir/sweep.csv" force "variant=$variant;p_percent=$p" "variant=$variant;p=$pr"
done < <(sed -n "/beside the paper's Fig. 8/,/(off-JND:/p" "$work/out" |
  sed -nE 's/^  ([a-z0-9+-]+) p=([0-9.]+) %[^0-9]* +([0-9.]+) % \+ *([0-9.]+) % +([0-9.]+) % \+ *([0-9.]+) % +([0-9.]+) %.*/\1 \2 \3 \4 \5 \6 \7/p')
check "the Fig. 8 table has its 10 rows (found $rows)" test "$rows" -eq 10

# The Fig. 12 table: "  DIRECTION, VARIANT[ (N Hz)], P % [CHAIN]   HERE %   PAPER %".
sphere_dir=$work/demo/sphere
rows=0
while IFS='|' read -r direction variant p chain here; do
  rows=$((rows + 1))
  pr=$(awk -v p="$p" 'BEGIN { print p / 100 }')
  check_figure "Fig. 12, $direction, $variant, p=$p %, $chain" "$here" "$sphere_dir/summary.csv" \
    "$sphere_dir/sweep.csv" "${direction}_rate_percent" "${direction}_packet_rate" \
    "direction=$direction;velocity_chain=$chain;variant=$variant;p_percent=$p" \
    "direction=$direction;velocity_chain=$chain;variant=$variant;p=$pr"
done < <(sed -n "/beside the paper's Fig. 12/,/(what is reproduced/p" "$work/out" |
  sed -nE 's/^  (velocity|force), (3-DoF|3-DoF[^,(]*[^ ,(])( \([0-9]+ Hz\))?, ([0-9.]+) % \[([^]]+)\] +([0-9.]+) %.*/\1|\2|\4|\5|\6/p')
check "the Fig. 12 table has its 9 rows (found $rows)" test "$rows" -eq 9

# The fidelity table's rows: every Fig. 8 and Fig. 12 row of docs/fidelity-table.md printed once, with the table's
# verdict, and each figure with its split the summary's: "  ID  HERE %  CONTACT % / FREE %  PAPER  WITHIN / DIRECTION".
table=$root/docs/fidelity-table.md
section=$(sed -n "/figures in the fidelity table/,/read both ways/p" "$work/out")
ids=$(sed -nE 's/^\| `((F8|F12|E12)-[^`]+)` .*/\1/p' "$table")
printed_rows=0
for id in $ids; do
  line=$(grep -E "^  $id " <<<"$section" || true)
  check "the demo prints the fidelity table's row $id" test -n "$line"
  want=$(awk -F'|' -v id="\`$id\`" '{ gsub(/ /, "", $2) } $2 == id { gsub(/ /, "", $7); gsub(/ /, "", $8); print $7 "/" $8 }' "$table")
  got=$(awk '{ print $(NF - 2) $(NF - 1) $NF }' <<<"$line")
  check "the demo's verdict for $id ($got) is the table's ($want)" test "$got" = "$want"
  [[ -n $line ]] && printed_rows=$((printed_rows + 1))
done
check "the fidelity table has its Fig. 8 and Fig. 12 rows (found $printed_rows)" test "$printed_rows" -ge 21
read -r _ here _ contact _ _ free _ <<<"$(grep -E '^  F8-15-as-force ' <<<"$section")"
for pair in "$here force_deadband_percent" "$contact force_deadband_contact_percent" "$free force_deadband_free_percent"; do
  read -r printed col <<<"$pair"
  check "F8-15-as-force: printed $printed is the summary's $col" \
    test "$printed" = "$(one_decimal "$(cell "$sweep_dir/summary.csv" "$col" "variant=deadband;p_percent=10")")"
done
read -r _ here _ contact _ _ free _ <<<"$(grep -E '^  F12-force-5-lp ' <<<"$section")"
for pair in "$here force_rate_percent" "$contact force_contact_percent" "$free force_free_percent"; do
  read -r printed col <<<"$pair"
  check "F12-force-5-lp: printed $printed is the summary's $col" test "$printed" = "$(one_decimal \
    "$(cell "$sphere_dir/summary.csv" "$col" "direction=force;velocity_chain=driver 20 Hz;variant=3-DoF LP;p_percent=5")")"
done

# sweep.csv against lever-hil run at one point of each table, seed 1, the sweep's duration.
duration=$(sed -nE 's/^sweep: [0-9]+ runs of ([0-9.]+) s .*/\1/p' "$work/out" | head -1)
check "the demo's sweeps say their duration ($duration)" test -n "$duration"
"$hil" run --scenario wall-tap --seed 1 --p 0.1 --duration "${duration:-1}" --topology one-controller \
  --gauge-chain dad141 --hsi-force-loop on --json >"$work/run.json"
for pair in "velocity_deadband_rate velocity_deadband_rate" "force_deadband_rate force_deadband_rate" \
  "velocity_packet_rate velocity_packet_rate" "force_jnd_violation force_jnd_violation"; do
  read -r rcol key <<<"$pair"
  got=$(cell "$sweep_dir/sweep.csv" "$rcol" "variant=deadband;p=0.1;seed=1")
  want=$(jq -r ".$key" "$work/run.json" | awk '{ printf "%.6f", $1 }')
  check "sweep.csv's deadband p=0.1 seed 1 $rcol $got is lever-hil run's $want" test "$got" = "$want"
done
"$hil" run --scenario sphere-3dof --seed 1 --p-velocity 0.2 --p-force 0 --delay-ms 0.2 --jitter-ms 0.1 \
  --duration "${duration:-1}" --json >"$work/sphere.json"
for key in velocity_packet_rate force_packet_rate; do
  got=$(cell "$sphere_dir/sweep.csv" "$key" "direction=velocity;velocity_chain=driver 20 Hz;variant=3-DoF;p=0.2;seed=1")
  want=$(jq -r ".$key" "$work/sphere.json" | awk '{ printf "%.6f", $1 }')
  check "sphere sweep.csv's velocity 3-DoF p=0.2 seed 1 $key $got is lever-hil run's $want" test "$got" = "$want"
done

# The simulated study session: labelled, its threshold the log's, its plot titled simulated.
study=$(sed -n "/^== lever-study:/,/^Plots:/p" "$work/out")
log=$work/demo/study/sim01.jsonl
check "the demo's study section is there and says SIMULATED" grep -q "^== lever-study: .* SIMULATED$" <<<"$study"
check "the demo's study summary marks the session simulated" grep -q "^SIMULATED sessions among these logs" <<<"$study"
check "the demo wrote a simulated session log" grep -q '"simulated":true' <(head -1 "$log")
threshold=$("$build/bin/lever-study" report --format csv "$log" | awk -F, 'NR == 2 { printf "%.2f%%", 100 * $7 }')
check "the demo's threshold ($(grep -E '^sim01 \*' <<<"$study" | awk '{ print $NF }')) is the log's ($threshold)" \
  grep -qE "^sim01 \* .* ${threshold}$" <<<"$study"
check "the demo's Fig. 7 plot is a PNG titled simulated" bash -c "test -s '$work/demo/study/fig7.png' &&
  grep -q 'set title \"SIMULATED sessions, not data: ' '$work/demo/study/plots.gp'"

report "demo tables"
