#!/usr/bin/env bash
# Bad input, class by class, against every program (docs/bad-input.md is the table this checks): each case
# asserts the exit code, the message, and what is left on disk. Every program runs under `timeout`: a hang
# is a failure, not a stuck test. The count of bad-input cases is printed at the end.
# usage: bad_input.sh lever-codec lever-hil lever-fw lever-bridge firmware/config lever-fw-sim
set -uo pipefail
codec=$(realpath "$1") hil=$(realpath "$2") fw=$(realpath "$3") bridge=$(realpath "$4") examples=$(realpath "$5")
fw_sim=$(realpath "$6")
source "$(dirname "$0")/lib.sh"
cases=0

run() {  # PROGRAM ARGS...: runs with a time limit; stdout in $work/out, stderr in $work/err, exit code in $code
  timeout 20 "$@" >"$work/out" 2>"$work/err"
  code=$?
}
# expect CODE NAME EXPECTED_MESSAGE PROGRAM ARGS...: one bad-input case; the message is one short line.
expect() {
  local want=$1 name=$2 expected=$3; shift 3
  cases=$((cases + 1))
  run "$@"
  check "$name: exit $want (got $code: $(head -c 300 "$work/err"))" test "$code" -eq "$want"
  check "$name: says '$expected'" grep -qF -- "$expected" "$work/err"
  check "$name: one line of at most 300 bytes" test "$(wc -l <"$work/err")" -le 1 -a "$(wc -c <"$work/err")" -le 300
}
no_temporaries() {  # NAME DIR: no hidden temporary of an atomic write left in DIR
  check "$1: no temporary left in $2 ($(ls -A "$2" | grep '^\.' | tr '\n' ' '))" \
    bash -c '! ls -A "$1" | grep -q "^\."' _ "$2"
}

# --- Exit codes, --help and --version: the same in every program -------------------------------------------
for p in "$codec" "$hil" "$fw" "$bridge" "$fw_sim"; do
  name=$(basename "$p")
  run "$p" --help
  check "$name --help: exit 0" test "$code" -eq 0
  # lever-bridge's footer says more of each code; the three are the same.
  check "$name --help states the exit codes" \
    grep -qE "Exit (codes|status): 0 success.*1 runtime failure.*2 bad input" <(tr '\n' ' ' <"$work/out")
  check "$name --help: no control bytes" bash -c "! LC_ALL=C grep -q '[[:cntrl:]]' <(tr -d '\n' <'$work/out')"
  run "$p" --version
  check "$name --version: exit 0" test "$code" -eq 0
  check "$name --version names the program and its version" grep -qE "^$name [0-9]+\.[0-9]+\.[0-9]+$" "$work/out"
done
for sub in run sweep serve; do
  run "$hil" "$sub" --help
  check "lever-hil $sub --help states the exit codes" grep -qF "Exit codes: 0 success" "$work/out"
  check "lever-hil $sub --help: no control bytes" bash -c "! LC_ALL=C grep -q '[[:cntrl:]]' <(tr -d '\n' <'$work/out')"
done
run "$hil" run --help
check "choices in help are the names, in order" grep -qF "{wall-tap, free-motion, press-hold, sphere-3dof}" "$work/out"
check "choices in help: no map arrows" bash -c "! grep -qE -- '[a-z]->[0-9]' '$work/out'"
run "$codec" generate --help
check "lever-codec generate --help lists the kinds" grep -qF "{velocity, force, force3}" "$work/out"

# --- Messages: subcommands, choices -------------------------------------------------------------------------
expect 2 "misspelt subcommand" "unknown subcommand 'rnu'; expected run, sweep, serve or study" "$hil" rnu --duration 1
expect 2 "no subcommand" "A subcommand is required" "$hil"
expect 2 "lever-codec: misspelt subcommand" "unknown subcommand 'genrate'; expected generate" "$codec" genrate
expect 2 "unknown scenario" "--scenario must be one of wall-tap, free-motion, press-hold, or sphere-3dof, got 'moonwalk'" \
  "$hil" run --scenario moonwalk
expect 2 "unknown mode" "--mode must be one of deadband or predictive, got 'zigzag'" "$codec" --mode zigzag --in x --out y
expect 2 "unknown kind" "--kind must be one of velocity, force, or force3, got 'heat'" "$codec" generate --kind heat --out x
expect 2 "lever-fw: unknown role" "--role must be one of hsi or top, got 'middle'" "$fw" --config x --role middle
expect 2 "a choice with control bytes is escaped" "got 'wall\\x1b[31m'" "$hil" run --scenario $'wall\e[31m'
expect 2 "a 100 kB choice is cut" "..." "$hil" run --scenario "$(head -c 100000 /dev/zero | tr '\0' x)"
expect 2 "a 100 kB fault is cut" "..." "$hil" run --fault "$(head -c 100000 /dev/zero | tr '\0' x)@1"

# --- Numbers: finite, in range, in the option's own terms ---------------------------------------------------
num() {  # NAME EXPECTED PROGRAM ARGS...: refused with exit 2 and no output file written
  local name=$1 expected=$2; shift 2
  rm -f "$work/o.csv"
  expect 2 "$name" "$expected" "$@"
  check "$name: no output" test ! -e "$work/o.csv"
}
"$codec" generate --kind force --duration 1 --out "$work/in.csv" >/dev/null
num "run --p nan" "--p must be a fraction in [0, 1), got 'nan'" "$hil" run --p nan --trace "$work/o.csv"
num "run --p -0.1" "--p must be a fraction in [0, 1), got -0.1" "$hil" run --p -0.1
num "run --p 1" "--p must be a fraction in [0, 1), got 1" "$hil" run --p 1
num "run --p-velocity inf" "--p-velocity must be a fraction in [0, 1), got 'inf'" "$hil" run --p-velocity inf
num "run --p-force 0x1p-3 (hex)" "--p-force must be" "$hil" run --p-force 0x1p-3
num "run --floor-force nan" "--floor-force must be a floor in N in [0, 65.535], got 'nan'" "$hil" run --floor-force nan
num "run --floor-velocity -1" "--floor-velocity must be a floor in rad/s" "$hil" run --floor-velocity -1
num "run --duration nan (hung)" "--duration must be a duration in seconds in [0.01, 86400], got 'nan'" \
  "$hil" run --duration nan --trace "$work/o.csv"
num "run --duration 1e300" "--duration must be a duration in seconds in [0.01, 86400], got 1e300" "$hil" run --duration 1e300
num "run --duration empty" "--duration must be" "$hil" run --duration ""
num "run --delay-ms 1e300 (overflowed to 0)" "--delay-ms must be a time in ms in [0, 60000], got 1e300" \
  "$hil" run --delay-ms 1e300
num "run --jitter-ms nan" "--jitter-ms must be a time in ms" "$hil" run --jitter-ms nan
num "run --loss 1.5" "--loss must be a probability in [0, 1], got 1.5" "$hil" run --loss 1.5
num "run --loss 1e999 (overflow)" "--loss must be a probability in [0, 1], got '1e999'" "$hil" run --loss 1e999
num "run --seed -1 (wrapped)" "--seed must be a seed in [0, 18446744073709551615], got '-1'" "$hil" run --seed -1
num "run --seed 2^64 (wrapped)" "--seed must be a seed" "$hil" run --seed 18446744073709551616
num "run --seed 1.5" "--seed must be a seed" "$hil" run --seed 1.5
num "run --filter-hz 500 (Nyquist)" "--filter-hz must be a cut-off in Hz below Nyquist (500 Hz at 1 kHz) in [0, 500), got 500" \
  "$hil" run --filter-hz 500
num "run --filter-hz-force nan" "--filter-hz-force must be" "$hil" run --filter-hz-force nan
num "run --comms-timeout-ms 2.5" "--comms-timeout-ms must be a whole number of milliseconds in [1, 10000], got '2.5'" \
  "$hil" run --comms-timeout-ms 2.5
num "run --comms-timeout-ms 1e300" "--comms-timeout-ms must be" "$hil" run --comms-timeout-ms 1e300
num "run --rest-repeat-ms -1" "--rest-repeat-ms must be a whole number of milliseconds in [0, 30000], got '-1'" \
  "$hil" run --rest-repeat-ms -1
num "sweep --floor-force -0.05 (as run refuses)" "--floor-force must be a floor in N in (0, 65.535], got -0.05" \
  "$hil" sweep --out "$work/sw" --floor-force -0.05
num "sweep --floor-velocity 0 (the +floor curve would not change)" "--floor-velocity must be a floor in rad/s in (0" \
  "$hil" sweep --out "$work/sw" --floor-velocity 0
num "sweep --filter-hz-velocity 500 (Nyquist)" "--filter-hz-velocity must be a cut-off in Hz below Nyquist" \
  "$hil" sweep --out "$work/sw" --filter-hz-velocity 500
num "sweep --filter-hz-force nan" "--filter-hz-force must be" "$hil" sweep --out "$work/sw" --filter-hz-force nan
num "sweep --over delay --p 1 (as run refuses)" "--p must be a fraction in [0, 1), got 1" \
  "$hil" sweep --out "$work/sw" --over delay --p 1
num "run --gauge-noise-n nan" "--gauge-noise-n must be a noise in N rms in [0, 1], got 'nan'" "$hil" run --gauge-noise-n nan
num "run --passivity-display-spend-s -1" "--passivity-display-spend-s must be a time in s in [0, 10], got -1" \
  "$hil" run --passivity-display-spend-s -1
num "run --passivity-reserve-share 1.5" "--passivity-reserve-share must be a share in [0, 1], got 1.5" \
  "$hil" run --passivity-reserve-share 1.5
num "run --passivity-drift-gain 1000" "--passivity-drift-gain must be a rate in 1/s in [0, 999], got 1000" \
  "$hil" run --passivity-drift-gain 1000
num "sweep --duration nan" "--duration must be" "$hil" sweep --out "$work/sw" --duration nan
num "sweep --seeds 0" "--seeds must be a whole number in [1, 100], got 0" "$hil" sweep --out "$work/sw" --seeds 0
num "sweep --jobs 1e9" "--jobs must be a whole number in [1, 64], got '1e9'" "$hil" sweep --out "$work/sw" --jobs 1e9
num "sweep --over delay --scenario sphere-3dof" "sweep --over delay runs wall-tap only" \
  "$hil" sweep --out "$work/sw" --over delay --scenario sphere-3dof
num "sweep --delays-ms nan" "--delays-ms must be a delay in ms in [0, 1000], got 'nan'" \
  "$hil" sweep --out "$work/sw" --over delay --delays-ms 0,nan
num "sweep --delays-ms -1" "--delays-ms must be a delay in ms in [0, 1000], got -1" \
  "$hil" sweep --out "$work/sw" --over delay --delays-ms -1
num "sweep --delays-ms 2000" "--delays-ms must be a delay in ms in [0, 1000], got 2000" \
  "$hil" sweep --out "$work/sw" --over delay --delays-ms 2000
num "sweep --delays-ms empty" "--delays-ms must be" "$hil" sweep --out "$work/sw" --over delay --delays-ms ""
num "sweep --delays-ms twice the same" "--delays-ms names a delay twice" \
  "$hil" sweep --out "$work/sw" --over delay --delays-ms 10,0,10
num "sweep --delays-ms without --over delay" "--delays-ms and --p belong to sweep --over delay" \
  "$hil" sweep --out "$work/sw" --delays-ms 10
num "sweep --over sideways" "--over" "$hil" sweep --out "$work/sw" --over sideways
check "the refused sweeps made no directory" test ! -e "$work/sw"
printf '[lever]\nrole = "hsi"\n' >"$work/hsi.toml"
printf '[lever]\nrole = "top"\n' >"$work/top.toml"
serve=(serve --hsi-config "$work/hsi.toml" --top-config "$work/top.toml")
num "serve --duration nan" "--duration must be a duration in seconds in [0, 86400], got 'nan'" "$hil" "${serve[@]}" --duration nan
num "serve --seed -1" "--seed must be a seed" "$hil" "${serve[@]}" --seed -1
num "serve --arm-timeout inf" "--arm-timeout must be a time in seconds" "$hil" "${serve[@]}" --arm-timeout inf
num "serve --max-edge-rate nan" "--max-edge-rate must be a rate in edges per second" "$hil" "${serve[@]}" --max-edge-rate nan
num "codec --p nan" "--p must be a fraction in [0, 1), got 'nan'" "$codec" --p nan --in "$work/in.csv" --out "$work/o.csv"
num "codec --p -0.1" "--p must be a fraction in [0, 1), got -0.1" "$codec" --p -0.1 --in "$work/in.csv" --out "$work/o.csv"
num "codec --floor nan" "--floor must be a floor in signal units >= 0, got 'nan'" \
  "$codec" --floor nan --in "$work/in.csv" --out "$work/o.csv"
num "codec --filter-hz 0" "--filter-hz must be a cut-off in Hz > 0, got 0" \
  "$codec" --filter-hz 0 --in "$work/in.csv" --out "$work/o.csv"
num "codec --filter-hz 800 (above the trace's Nyquist)" \
  "--filter-hz must be below the trace's Nyquist frequency (500 Hz at 1000 Hz), got 800" \
  "$codec" --filter-hz 800 --in "$work/in.csv" --out "$work/o.csv"
num "generate --duration nan (hung, 3.8 GB)" "--duration must be a duration in seconds in [0.001, 3600], got 'nan'" \
  "$codec" generate --kind force --duration nan --out "$work/o.csv"
num "generate --duration 1e300" "--duration must be" "$codec" generate --kind force --duration 1e300 --out "$work/o.csv"
num "generate --seed -1 (wrapped)" "--seed must be a seed in [0, 18446744073709551615], got '-1'" \
  "$codec" generate --kind force --seed -1 --out "$work/o.csv"
num "generate --seed 2^64" "--seed must be a seed" "$codec" generate --kind force --seed 99999999999999999999 --out "$work/o.csv"
num "lever-fw-sim --duration nan" "--duration must be a duration in seconds in [0.1, 86400], got 'nan'" \
  "$fw_sim" --config "$examples/top.toml" --duration nan
num "lever-fw-sim --duration -1" "--duration must be" "$fw_sim" --config "$examples/top.toml" --duration -1
num "lever-bridge --site-id nan" "--site-id must be a whole number in [0, 255], got 'nan'" "$bridge" --site-id nan
num "lever-bridge --site-id 256" "--site-id must be a whole number in [0, 255], got 256" "$bridge" --site-id 256
num "lever-bridge --realtime-priority 1.5" "--realtime-priority must be a whole number in [0, 99], got '1.5'" \
  "$bridge" --realtime-priority 1.5
expect 2 "lever-bridge: misspelt subcommand" "unknown subcommand 'kegen'; expected keygen" "$bridge" kegen
# The same check for configuration keys (lever-fw's TOML, read by lever-fw and lever-hil serve).
printf '[codec.force]\np = nan\n' >"$work/nan.toml"
expect 2 "config key NaN" "codec.force.p: must be a fraction in [0, 1), got nan" "$fw" --config "$work/nan.toml" --check-config
printf '[safety]\ntorque_limit_nm = 1e300\n' >"$work/big.toml"
expect 2 "config key 1e300" "safety.torque_limit_nm: must be a number of N m in" "$fw" --config "$work/big.toml" --check-config
check "config key 1e300: short numbers" bash -c "! grep -qE '[0-9]{20}' '$work/err'"
printf '[lever]\nrole = "hsi"\n[codec.motion]\nfilter_hz = inf\n' >"$work/inf.toml"
expect 2 "serve: a config key that is inf" "codec.motion.filter_hz: must be" "$hil" serve --hsi-config "$work/inf.toml" \
  --top-config "$work/top.toml"

# --- Silent acceptance ---------------------------------------------------------------------------------------
expect 2 "a site for link-down, which ignores it" "link-down affects the link between both sites and takes no ':top'" \
  "$hil" run --fault link-down@5+0.5:top
expect 2 "a site for burst-loss" "takes no ':hsi'" "$hil" run --fault burst-loss@5+0.5:hsi
expect 2 "a fault after the end of the run" "fault 'bus-off@30' starts at 30 s, after the run's 20 s (--duration)" \
  "$hil" run --fault bus-off@30
expect 2 "a fault at the very end" "starts at 2 s, after the run's 2 s" "$hil" run --duration 2 --fault bus-off@2
expect 2 "a delay step of 1e300 ms" "is over 60000" "$hil" run --fault delay-step@1:1e300
expect 2 "a fault start of nan" "is not a non-negative number" "$hil" run --fault link-down@nan
expect 2 "a network delay in one controller" "one controller has no network" \
  "$hil" run --topology one-controller --delay-ms 5
expect 2 "a link fault in one controller" "fault 'link-down@1' needs a bus or a link: one controller has neither" \
  "$hil" run --topology one-controller --fault link-down@1
expect 2 "a lever-only option for the sphere" "--encoder-counts, --encoder-interface and --hsi-force-loop belong to" \
  "$hil" run --scenario sphere-3dof --hsi-force-loop on
expect 2 "a sphere-only option for a lever" "--device-velocity and --driver-cutoff-hz belong to sphere-3dof" \
  "$hil" run --driver-cutoff-hz 10
expect 2 "sweep's lever options for the sphere" "--topology and --hsi-force-loop belong to the lever scenarios" \
  "$hil" sweep --scenario sphere-3dof --out "$work/none" --topology one-site
run "$hil" run --duration 2 --fault link-down@1+0.2 --json
check "a good fault still runs: exit 0" test "$code" -eq 0

# --- Output files -------------------------------------------------------------------------------------------
# Each writer against each kind of target it must refuse; the target is what it was afterwards.
mkdir -p "$work/t" && cd "$work/t" || exit 1
"$codec" generate --kind force --duration 0.2 --out in.csv >/dev/null
cp in.csv in.orig
writers=(
  "codec --out|$codec --in in.csv --out"
  "generate --out|$codec generate --kind force --duration 0.2 --out"
  "run --trace|$hil run --duration 0.5 --trace"
)
# A character device of our own (the null device's numbers), so that a regression replaces a node in the
# scratch directory, never the machine's /dev/null. Without root (no mknod) /dev/null stands in: a user
# cannot rename over it anyway.
if mknod chardev c 1 3 2>/dev/null; then dev=chardev; else dev=/dev/null; fi
mkfifo fifo
mkdir adir
echo keep >target.txt
ln -s target.txt link
for w in "${writers[@]}"; do
  name=${w%%|*}; read -ra cmd <<<"${w#*|}"
  expect 2 "$name a character device (/dev/null was replaced as root)" "$dev is a character device" "${cmd[@]}" "$dev"
  check "$name a character device: still one" test -c "$dev"
  expect 2 "$name a FIFO (no hang)" "fifo is a FIFO" "${cmd[@]}" fifo
  check "$name a FIFO: still one" test -p fifo
  expect 2 "$name a directory" "adir is a directory" "${cmd[@]}" adir
  expect 2 "$name a trailing slash" "names a directory" "${cmd[@]}" newdir/
  check "$name a directory: still one, empty" test -d adir -a -z "$(ls -A adir)"
  expect 2 "$name a symbolic link" "link is a symbolic link" "${cmd[@]}" link
  check "$name a symbolic link: still one, its target unchanged" test -L link -a "$(cat target.txt)" = keep
  expect 2 "$name a missing directory" "the directory no/such does not exist" "${cmd[@]}" no/such/out.csv
  check "$name a missing directory: not created" test ! -e no
  expect 2 "$name an empty path" "must be a path, got ''" "${cmd[@]}" ""
  no_temporaries "$name" .
done
expect 2 "codec: the input as output" "--out in.csv is the input file in.csv" "$codec" --in in.csv --out in.csv
expect 2 "codec: the input under another name" "is the input file" "$codec" --in ./in.csv --out "$work/t/in.csv"
ln in.csv hard.csv
expect 2 "codec: a hard link to the input" "is the input file" "$codec" --in in.csv --out hard.csv
check "the input is unchanged" cmp -s in.csv in.orig
no_temporaries "input as output" .
# A regular file is replaced whole, with the umask's mode; '-' is stdout and stdin.
echo old >o.csv
run "$codec" --in in.csv --out o.csv
check "a regular file is replaced: exit 0" test "$code" -eq 0
check "a regular file is replaced: the header" test "$(head -1 o.csv)" = "t,sent,x_hat"
check "a regular file is replaced: mode from the umask" test "$(stat -c %a o.csv)" = "$(printf '%o' $((0666 & ~$(umask))))"
run "$codec" --in - --out - <in.csv
check "'-' reads stdin and writes stdout: exit 0" test "$code" -eq 0
check "'-': the CSV on stdout" cmp -s o.csv "$work/out"
check "'-': the summary on stderr" jq -e '.samples == 200' "$work/err" >/dev/null
run "$codec" generate --kind force --duration 0.2 --out -
check "generate --out -: the trace on stdout" cmp -s in.csv "$work/out"
run "$hil" run --duration 0.5 --trace - --json
check "run --trace -: the trace on stdout" test "$(head -1 "$work/out" | cut -d, -f1-3)" = "t,hsi_angle,top_angle"
check "run --trace -: the report on stderr" jq -e 'has("velocity_packet_rate")' "$work/err" >/dev/null
# A write failure says errno's reason.
cases=$((cases + 1))
timeout 20 "$codec" --in in.csv --out - >/dev/full 2>"$work/err"; code=$?
check "a full disk: exit 1 (got $code)" test "$code" -eq 1
check "a full disk: says why" grep -qF "cannot write --out -: No space left on device" "$work/err"
no_temporaries "after the good runs" .

# Signals: the temporary is removed, the target untouched, the signal's default action (128 + its number).
# `env --default-signal` undoes the SIG_IGN a non-interactive shell gives background jobs for SIGINT.
echo keep >sig.csv
for sig in INT TERM HUP; do
  cases=$((cases + 1))
  env --default-signal=INT "$hil" run --duration 86400 --trace sig.csv >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 50); do ls -A | grep -q '^\.sig\.csv' && break; sleep 0.1; done
  check "SIG$sig: the run has its temporary" bash -c "ls -A | grep -q '^\\.sig\\.csv'"
  kill -"$sig" "$pid"; wait "$pid"; code=$?
  check "SIG$sig: killed by it (exit $code)" test "$code" -eq $((128 + $(kill -l "$sig")))
  check "SIG$sig: the target untouched" test "$(cat sig.csv)" = keep
  no_temporaries "SIG$sig" .
done
mkfifo slow
cases=$((cases + 1))
env --default-signal=INT "$codec" --in slow --out sig.csv >/dev/null 2>&1 &
pid=$!
exec 7<>slow  # a writer that never writes (read-write: never blocks): the reader waits with its temporary made
for _ in $(seq 50); do ls -A | grep -q '^\.sig\.csv' && break; sleep 0.1; done
kill -TERM "$pid"; wait "$pid"; code=$?
exec 7>&-
check "lever-codec SIGTERM while reading: exit 143 (got $code)" test "$code" -eq 143
no_temporaries "lever-codec SIGTERM" .

# lever-hil run --trace streams: an hour's trace is no longer held whole (it was 1.1 GB). 300 s of trace
# (36 MB of rows held before) must not grow the peak memory by more than 8 MB over a run without one.
rss() { /usr/bin/time -f %M "$@" 2>&1 >/dev/null | tail -1; }
base=$(rss "$hil" run --duration 300 --json)
traced=$(rss "$hil" run --duration 300 --json --trace big.csv)
check "run --trace streams: peak RSS $base kB without, $traced kB with" test $((traced - base)) -lt 8192
check "run --trace streams: every row written" test "$(wc -l <big.csv)" -eq 300001
rm -f big.csv

# Input files: a BOM is skipped; huge and control-laden fields are cut and escaped.
printf '\xef\xbb\xbft,x\n0,1\n0.001,2\n' >bom.csv
run "$codec" --in bom.csv --out o.csv
check "a UTF-8 BOM before the header is skipped: exit 0 ($(cat "$work/err"))" test "$code" -eq 0
{ printf 't,x\n0,'; head -c 100000 /dev/zero | tr '\0' 9; printf 'x\n'; } >huge.csv
expect 2 "a 100 kB field" "huge.csv:2: '999999999999" "$codec" --in huge.csv --out o.csv
printf 't,x\n0,1\x1b[2J\n' >ctl.csv
expect 2 "a field with control bytes" "'1\\x1b[2J' in column 'x' is not a number" "$codec" --in ctl.csv --out o.csv
expect 2 "an input directory" "adir" "$codec" --in adir --out o.csv

# --- Plots: paths are data, never gnuplot or shell code; the script runs from anywhere --------------------
if command -v gnuplot >/dev/null; then
  # A name that is a shell command inside single quotes, and one that is gnuplot code inside double quotes.
  gp_evil="$work/t/g\" . system(\"touch $work/t/pwned2\") . \""
  run "$hil" sweep --out "$gp_evil" --seeds 1 --duration 0.1
  check "sweep into a directory named with gnuplot code: exit 0 ($(tail -1 "$work/err"))" test "$code" -eq 0
  check "sweep: the gnuplot code did not run" test ! -e pwned2
  evil="$work/t/a'\$(touch $work/t/pwned)'b"
  run "$hil" sweep --out "$evil" --seeds 2 --duration 0.1
  check "sweep into a directory named with quotes and \$(...): exit 0 ($(tail -1 "$work/err"))" test "$code" -eq 0
  check "sweep: the shell command did not run" test ! -e pwned
  check "sweep: the plots are there" test -s "$evil/packet_rate_velocity.png" -a -s "$evil/position_error.png"
  check "sweep: the summary states seeds and spread" \
    grep -q "^variant,p_percent,seeds,velocity_rate_percent,velocity_rate_percent_min,velocity_rate_percent_max" "$evil/summary.csv"
  check "sweep: every point of 2 seeds" test "$(tail -n +2 "$evil/summary.csv" | cut -d, -f3 | sort -u)" = 2
  check "sweep: the titles state the seeds and the bars" grep -qF 'mean of 2 seeds; bars: min to max"' "$evil/plots.gp"
  check "sweep: the legend is below the plot" grep -qx "set key below horizontal" "$evil/plots.gp"
  rm "$evil"/*.png
  (cd / && gnuplot "$evil/plots.gp") 2>"$work/err"
  check "the plot script runs from another directory ($(head -c 200 "$work/err"))" test -s "$evil/distortion.png"
  no_temporaries "sweep" "$evil"
  # The 3-DoF scenario's sweep writes its own script: the same rules.
  run "$hil" sweep --scenario sphere-3dof --out "$evil" --seeds 1 --duration 0.1
  check "sphere-3dof sweep into the same directory: exit 0 ($(tail -1 "$work/err"))" test "$code" -eq 0
  check "sphere-3dof sweep: the shell command did not run" test ! -e pwned
  check "sphere-3dof sweep: its plots are there" test -s "$evil/fig12_packet_rates.png"
fi
expect 2 "sphere-3dof run --trace a directory" "--trace adir is a directory" "$hil" run --scenario sphere-3dof --trace adir
expect 2 "sphere-3dof run --trace a FIFO" "--trace fifo is a FIFO" "$hil" run --scenario sphere-3dof --trace fifo
echo file >afile
expect 2 "sweep --out a file" "--out afile exists and is not a directory" "$hil" sweep --out afile --duration 0.1
check "sweep --out a file: the file untouched" test "$(cat afile)" = file
mkdir sw2 && mkfifo sw2/summary.csv
expect 2 "sweep --out with summary.csv a FIFO" "summary.csv is a FIFO" "$hil" sweep --out sw2 --duration 0.1
check "sweep --out with a FIFO: refused before the runs (no sweep.csv)" test ! -e sw2/sweep.csv
expect 2 "serve --trace a directory, before any device" "--trace adir is a directory" "$hil" "${serve[@]}" --trace adir
cd / || exit 1

echo "bad-input cases: $cases"
report "bad input"
