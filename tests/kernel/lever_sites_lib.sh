# Sourced by the kernel-rig tests that run real lever-fw processes behind `lever-hil serve` (run-in-guest
# --gpio-sim --pwm-sim --virtual-time), after lib.sh and gpio_sim_lib.sh. Each lever gets two gpio-sim chips with
# the lines its config names by default: the encoder's, named after its role (ENC_A, ENC_B), and the motor driver's,
# ROLE-motor (MOTOR_EN, MOTOR_DIR, MOTOR_FAULT), as a board's encoder and driver lines sit on different controllers
# (why two: lever_chip), a PWM channel of the kernel's PWM core (the rig's simulated controllers: the HSI's pwmchip0, the TOP's
# pwmchip1), and a config file $work/<role>.toml.
#
# The guest runs in virtual time (one vCPU, 1 ns an instruction): every timer fires on time in guest time, so
# the levers run the example configurations as a board would. A config is the example file with only the keys
# that name where this guest's devices are (the CAN interface, the gpio-sim chip, the TOP's PWM chip) changed;
# write_config prints them. Everything a closed loop touches (the PWM trees, the status lines,
# candump's log, serve's report and trace) lives in the guest (tmpfs, sysfs) while the run is on: the results share is
# 9p to the host, whose I/O is not synchronised with virtual time. collect_results copies it all out at the end.
#
# Repeatability: the guest's own timers are deterministic in virtual time, but every program started (a poll's
# jq, a sleep) is read from the host over 9p, and lands when the host answers. The steps before a
# scenario (starting the programs, homing and arming by lever-ctl) therefore start at virtual times that
# differ from run to run. What keeps that from reaching the scenario: lever-fw's loops and serve's ticks fall on
# whole milliseconds of CLOCK_MONOTONIC (one phase however they were started), serve re-seeds the world's noise
# when the scenario starts, and the tests wait for the scenario's end with `wait`, starting no program while it
# runs. What still differs is said in docs/hil-serve.md ("Repeatability").
results=$out
out=$(mktemp -d -p /dev/shm)
examples=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../firmware/config" && pwd)
# What the harness runs again and again while the levers run (its polls) must not be read from the host each
# time: in virtual time a 9p round trip costs no guest time but all the host's, and polls made of them took most
# of a run's wall time. So sleep, tail and grep are bash's own here, and jq runs from the guest's memory: its
# binary and libraries copied once, started through the copied dynamic loader.
guest_tools=$(mktemp -d -p /dev/shm)
exec {never_ready}<> <(:)
sleep() { read -rt "$1" -u "$never_ready" || :; }
last_line() {  # last_line FILE: its last line (nothing when there is none)
  local line last=''
  [[ -r $1 ]] || return 1
  while IFS= read -r line || [[ -n $line ]]; do last=$line; done <"$1"
  printf '%s\n' "$last"
}
has_text() { [[ -r $1 && $(<"$1") == *"$2"* ]]; }  # has_text FILE TEXT
pin_tool() {  # pin_tool NAME [PATH]: from here on a function NAME runs the guest's copy (of PATH, or NAME's)
  local path=${2:-} lib loader
  [[ -n $path ]] || path=$(type -P "$1") || { echo "FAILED: no $1 to copy into the guest" >&2; return 1; }
  cp "$path" "$guest_tools/$1"
  while read -r lib; do cp -nL "$lib" "$guest_tools/"; done < <(ldd "$path" | awk '$2 == "=>" && $3 ~ /^\// { print $3 }')
  loader=$(ldd "$path" | awk '$1 ~ /^\/.*ld-linux/ { print $1 }')
  cp -L "$loader" "$guest_tools/ld.so"
  # HOME too: jq looks for ~/.jq at each start.
  eval "$1() { HOME=\"$guest_tools\" \"$guest_tools/ld.so\" --inhibit-cache --library-path \"$guest_tools\" \"$guest_tools/$1\" \"\$@\"; }"
}
pin_tool jq || exit 1
dbc=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/common/protocol/lever.dbc
dbc_decode=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/tools/dbc-decode
pids=()

# lever_chip ROLE: its gpio-sim chips; ROLE_gpio is the motor chip's sysfs directory (sim_gpioN/value: line N, MOTOR_EN
# is line 0), ROLE_encoder_gpio the encoder chip's. Two chips, not one: gpio-sim serves a chip under one mutex, which
# the world takes for each of up to 20000 encoder edges a second; a lever's loop writing its direction line or reading
# back its enable line on the same chip would wait for it whenever an ordinary process preempted the world holding it
# (docs/deploy.md, "The board's kernel", finding 3). A board's encoder is a counter or a GPIO bank of its own.
lever_chip() {
  sim_chip "$1" ENC_A ENC_B >/dev/null || return 1
  printf -v "${1}_encoder_gpio" '%s' "$LEVER_GPIO_SYSFS"
  sim_chip "$1-motor" MOTOR_EN MOTOR_DIR MOTOR_FAULT >/dev/null || return 1
  printf -v "${1}_gpio" '%s' "$LEVER_GPIO_SYSFS"
}
pwm_chips() {  # the rig's simulated PWM controllers are there, one per lever, none exported yet
  local role dir
  for role in hsi top; do
    dir=/sys/class/pwm/pwmchip$(pwm_chip $role)
    [[ $(basename "$(readlink -f "$dir/device")") == lever-pwm-sim.$(pwm_chip $role) && ! -e $dir/pwm0 ]] ||
      { echo "FAILED: $dir is not a fresh lever-pwm-sim chip (run-in-guest --pwm-sim?)" >&2; return 1; }
  done
}

# write_config ROLE CAN_INTERFACE [SECTION KEY VALUE]...: $work/ROLE.toml, the example config with the devices
# of this guest and the given keys changed (VALUE a TOML value), as lever-fw resolves it (--set, --check-config: each
# key checked as in a file, every key written out), also installed in $installed_configs where a test sets it (the
# board image's /etc/lever); prints every key that differs from the example
write_config() {
  local role=$1 can=$2 file=$work/$1.toml; shift 2
  local sets=(--set "board.can.interface=\"$can\"" --set "board.encoder.chip=\"$role\"" --set "board.motor.line_chip=\"$role-motor\"")
  [[ $role == top ]] && sets+=(--set "board.motor.pwm_chip=$(pwm_chip top)")
  while (($# >= 3)); do sets+=(--set "$1.$2=$3"); shift 3; done
  "$bin/lever-fw" --config "$examples/$role.toml" "${sets[@]}" --check-config >"$file" ||
    { echo "FAILED: lever-fw refused $role.toml's keys: ${sets[*]}" >&2; exit 1; }
  [[ -z ${installed_configs:-} ]] || install -m 0644 "$file" "$installed_configs/$role.toml" || exit 1
  echo "${installed_configs:+$installed_configs/}$role.toml differs from the example in:"
  diff <("$bin/lever-fw" --config "$examples/$role.toml" --check-config | sed 1d) <(sed 1d "$file") | sed -n 's/^> /  /p'
}

# key ROLE SECTION KEY: a figure of the lever's configuration ($work/ROLE.toml), which the bounds come from, as
# lever-fw resolves it (its default where the file leaves the key out)
key() { "$bin/lever-fw" --config "$work/$1.toml" --get "$2.$3"; }
# example_key ROLE SECTION KEY: the same figure of the example configuration the lever's was made from (what ships),
# for a bound that must not follow a lever configured otherwise
example_key() { "$bin/lever-fw" --config "$examples/$1.toml" --get "$2.$3"; }

# one_site NAME SERVE_ARGS...: both levers on one bus (the TOP's gauge on Modbus TCP), candump logging the HSI's
# interface to $out/NAME.candump, serve started, then both lever-fw. The bus is vcan0 for both, or with
# site_bus=kvaser the emulated SJA1000 controllers of run-in-guest --kvaser, on one emulated bus: the HSI on can0,
# the TOP on can1. Extra config keys for the HSI in $one_site_hsi_keys (SECTION KEY VALUE...).
site_bus=vcan
one_site_hsi_keys=()
one_site() {
  local name=$1; shift
  lever_chip hsi && lever_chip top && pwm_chips || exit 1
  write_config hsi "$(site_can hsi)" "${one_site_hsi_keys[@]}"
  write_config top "$(site_can top)"
  candump -r 8388608 -L "$(site_can hsi)" >"$out/$name.candump" &
  pids+=("$!")
  start_serve "$name" "$@" || exit 1
  start_fw hsi
  start_fw top
}

# site_can ROLE: the lever's CAN interface at one site
site_can() {
  if [[ $site_bus == kvaser ]]; then [[ $1 == hsi ]] && echo can0 || echo can1; else echo vcan0; fi
}

# two_sites NAME SERVE_ARGS...: the HSI on vcan0, the TOP on vcan1 (its gauge on Modbus RTU over a pty), joined by
# two lever-bridges over UDP on loopback; candump logging vcan0 to $out/NAME-hsi.candump; serve started, then both
# lever-fw. Extra config keys for both levers in $two_sites_keys (SECTION KEY VALUE...).
two_sites_keys=()
two_sites() {
  local name=$1; shift
  lever_chip hsi && lever_chip top && pwm_chips || exit 1
  write_config hsi vcan0 "${two_sites_keys[@]}"
  write_config top vcan1 board.gauge transport '"rtu"' board.gauge device "\"$work/top-gauge.tty\"" \
    "${two_sites_keys[@]}"
  "$bin/lever-bridge" --can vcan0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key" --site-id 1 \
    --stats-json >"$out/bridge-hsi.stats" 2>"$out/bridge-hsi.err" &
  pids+=("$!")
  "$bin/lever-bridge" --can vcan1 --bind 127.0.0.1:5001 --peer 127.0.0.1:5000 --key "$key" --site-id 2 \
    --stats-json >"$out/bridge-top.stats" 2>"$out/bridge-top.err" &
  pids+=("$!")
  candump -r 8388608 -L vcan0 >"$out/$name-hsi.candump" &
  pids+=("$!")
  start_serve "$name" "$@" || exit 1
  start_fw hsi
  start_fw top
}

# start_serve NAME ARGS...: lever-hil serve in the background, waiting until its devices are up
start_serve() {
  local name=$1; shift
  "$bin/lever-hil" serve --hsi-config "$work/hsi.toml" --top-config "$work/top.toml" "$@" \
    >"$out/$name.report" 2>"$out/$name.serve" &
  serve_pid=$!
  pids+=("$serve_pid")
  for _ in $(seq 600); do
    has_text "$out/$name.serve" "waiting for both" && return 0
    kill -0 "$serve_pid" 2>/dev/null || break
    sleep 0.1
  done
  echo "FAILED: lever-hil serve did not come up:" >&2
  cat "$out/$name.serve" >&2
  return 1
}

# start_fw ROLE: lever-fw with its status lines in $out/ROLE.stats (appended: a restarted lever goes on), and its
# motor state in $out/ROLE.motor (for a lever-fw --motor-off, as the service's)
start_fw() {
  "$bin/lever-fw" --config "$work/$1.toml" --motor-state "$out/$1.motor" --stats-json >>"$out/$1.stats" \
    2>>"$out/$1.err" &
  eval "${1}_pid=$!"
  pids+=("$!")
}

# wait_for_serve NAME TEXT: until serve's log says it (120 s)
wait_for_serve() {
  local deadline=$((SECONDS + 120))
  while ((SECONDS < deadline)); do has_text "$out/$1.serve" "$2" && return 0; sleep 0.2; done
  echo "timed out waiting for serve to say '$2'" >&2
  return 1
}

# log_mark CANDUMP_LOG: its line count now; heard_armed CANDUMP_LOG MARK ROLE: the lever's heartbeat said armed
# (State=2) in a frame logged after the mark. The status lines come once a second; heartbeats 40 times.
log_mark() { wc -l <"$1"; }
heard_armed() {
  local name=LeverHeartbeatHsi deadline=$((SECONDS + 30))
  [[ $3 == top ]] && name=LeverHeartbeatTop
  while ((SECONDS < deadline)); do
    tail -n +"$(($2 + 1))" "$1" | "$dbc_decode" "$dbc" 2>/dev/null | grep -q "$name State=2 " && return 0
    sleep 0.5
  done
  return 1
}

# last_stat ROLE JQ: the expression on the lever's newest status line
last_stat() { last_line "$out/$1.stats" 2>/dev/null | jq -r "$2" 2>/dev/null; }

# wait_for SECONDS ROLE JQ_CONDITION: until the lever's newest status line satisfies it
wait_for() {
  local role=$2 condition=$3 deadline=$((SECONDS + $1))
  while ((SECONDS < deadline)); do
    [[ $(last_stat "$role" "$condition") == true ]] && return 0
    sleep 0.2
  done
  echo "timed out after ${1}s waiting for $role: $condition (last: $(last_line "$out/$role.stats"))" >&2
  return 1
}

# no_guard_fired ROLE...: each lever's motor guard started and none has fired. A lever starting beside another on
# one CPU must not stall the running loop past its guard's deadline (docs/deploy.md, "The board's kernel"). The
# guard's start line makes an empty or missing log fail rather than pass.
no_guard_fired() {
  local role
  for role; do
    has_text "$out/$role.err" "motor guard pid" || { echo "$role: no motor guard started (its log: $out/$role.err)" >&2; return 1; }
    ! has_text "$out/$role.err" "loop has not stepped for" || return 1
  done
}

# up_and_homed: both levers up disarmed, then homed by lever-ctl home (the checks every pair test starts with;
# arming is each test's own)
up_and_homed() {
  require "both levers come up disarmed" wait_for 60 hsi '.state == "disarmed"'
  require "(TOP too)" wait_for 60 top '.state == "disarmed"'
  check "and neither lever's motor guard fired while both started" no_guard_fired hsi top
  require "lever-ctl home: both levers' heartbeats say homed" lever_ctl vcan0 home
  require "both home (status lines)" wait_for 120 hsi '.position_valid'
  require "(TOP too)" wait_for 120 top '.position_valid'
}

# lever_ctl CAN VERB [OPTION...]: the pair (pair 0) operated as a user does, by lever-ctl, which resends the
# command until both levers' heartbeats show its state; its exit status (0 done, 1 refused or timed out), and
# its report (which lever, why) in $out/lever-ctl.log and on stdout
pin_tool lever-ctl "$bin/lever-ctl" || exit 1
lever_ctl() {
  local can=$1 verb=$2 code; shift 2
  lever-ctl "$verb" --pair 0 --can "$can" "$@" >>"$out/lever-ctl.log" 2>&1; code=$?
  echo "lever-ctl $verb (exit $code): $(last_line "$out/lever-ctl.log")"
  return "$code"
}

# command CAN OPCODE: the command to both levers of pair 0 by its opcode (1 arm, 2 disarm, 3 rearm, 6 home), by
# lever_ctl
command() {
  local -A verbs=([1]=arm [2]=disarm [3]=rearm [4]=tare [6]=home)
  [[ -n ${verbs[$2]:-} ]] || { echo "FAILED: command: no opcode $2" >&2; return 2; }
  lever_ctl "$1" "${verbs[$2]}"
}

# stat_true ROLE FILTER: jq_true (lib.sh) on the lever's newest status line.
stat_true() { last_line "$out/$1.stats" 2>/dev/null | jq_true - "$2"; }

# check_one_site_report REPORT: the one-site scenario's bounds on serve's report (lever_one_site.sh, and the same
# pair under systemd on the board image, tests/image/pair_units.sh)
# check_one_site_run REPORT [CODE]: serve's 15 s scenario ended (waited for without a poll: no program is started
# while it runs, for repeatability; CODE is its exit status where the caller waited), its report within
# lever_one_site's bounds, no encoder edge lost, and the motors driven through the kernel's PWM core to the
# (simulated) controllers, whose outputs serve read back as torques.
check_one_site_run() {
  local code=${2-} role hw_enabled hw_period hw_duty hw_polarity hw_applies hw_last_ns
  [[ -n $code ]] || { wait "$serve_pid"; code=$?; }
  check "lever-hil serve ran its 15 s scenario and exited 0 (got $code)" test "$code" -eq 0
  check_one_site_report "$1"
  check "no encoder edge lost" test "$(last_stat hsi .encoder.lost)/$(last_stat top .encoder.lost)" = 0/0
  for role in hsi top; do
    read -r hw_enabled hw_period hw_duty hw_polarity hw_applies hw_last_ns hw_pin <<<"$(pwm_hw $role)"
    check "$role: its PWM controller was programmed through the kernel's PWM core: $hw_applies states, the last one $(pwm_hw $role)" \
      test "$hw_period $hw_polarity" = "50000 normal" -a "$hw_applies" -gt 100
  done
}

check_one_site_report() {
  local report=$1
  jq . "$report"
  r() { jq -r "$1" "$report"; }
  # Bounds, from the physics before the run: the TOP's position loop (40 N m/rad) saturates at the 1 N m torque
  # limit 25 mrad away from its reference, so tracking within that on average is what the loop can do; in
  # contact the HSI goes past the wall the TOP stops at, by the displayed force over the operator's stiffness
  # (up to ~10 N x 0.1 m / 3 N m/rad = 0.33 rad), which bounds the largest difference. (Under TCG these fail:
  # docs/hil-serve.md, "What the emulator cannot show".)
  check "both levers stayed armed through the scenario (armed $(r .armed_s) s)" test "$(r '.armed_s >= 14.5')" = true
  check "the TOP follows the HSI: rms error $(r .position_rmse) rad < 0.025" test "$(r '.position_rmse < 0.025')" = true
  check "largest error $(r .serve.max_position_error_rad) rad < 0.35" test "$(r '.serve.max_position_error_rad < 0.35')" = true
  check "the TOP touches the wall ($(r .contact_share) of the time, $(r .mean_contact_force_n) N)" \
    test "$(r '.contact_share > 0.05 and .mean_contact_force_n > 0.5')" = true
  check "the wall force comes back to the HSI's bus (up to $(r .serve.max_displayed_force_n) N)" \
    test "$(r '.serve.max_displayed_force_n > 1')" = true
  check "and the HSI's motor pushes the operator back in contact ($(r .serve.mean_hsi_torque_in_contact_nm) N m)" \
    test "$(r '.serve.mean_hsi_torque_in_contact_nm < -0.05')" = true
  check "packet rates below 1 kHz: velocity $(r .velocity_packet_rate), force $(r .force_packet_rate)" \
    test "$(r '.velocity_packet_rate > 0 and .velocity_packet_rate < 0.9 and .force_packet_rate > 0 and .force_packet_rate < 0.9')" = true
  check "the TOP's lever-fw polled the Modbus gauge ($(r .serve.gauge_requests) requests)" \
    test "$(r '.serve.gauge_requests > 100')" = true
  check "the HSI displayed a remote force" test "$(jq -s 'map(.remote // 0) | max > 1' "$out/hsi.stats")" = true
}

# pwm_chip ROLE: the number of the lever's PWM chip
pwm_chip() { [[ $1 == hsi ]] && echo 0 || echo 1; }
# pwm_state ROLE: the lever's PWM channel as the kernel's PWM core holds it, "enable duty_cycle"
pwm_state() {
  local dir=/sys/class/pwm/pwmchip$(pwm_chip "$1")/pwm0
  echo "$(cat "$dir/enable") $(cat "$dir/duty_cycle")"
}
# pwm_hw ROLE: what the simulated controller was last programmed with, and what its pin puts out: "enabled period
# duty polarity applies last_apply_ns pin_ppm"
pwm_hw() { cat "/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/hw_state"; }
# pin_inactive ROLE PIN_PPM: a pin putting out PIN_PPM (the controller's pin_ppm: millionths of a period high)
# gives the lever's driver no duty: low all the time, or high all the time when the board inverts it on its way
# ([board.motor] pwm_inversed of $work/ROLE.toml, read once: a fork in a timed poll costs milliseconds of guest
# time). The pin's output, never the controller's enabled flag: a disabled PWM's output is undefined, and the
# rig's controller holds it where it was (tools/kernel-rig/README.md, "Simulated PWM").
pin_inactive() {
  local inverted=inverted_$1
  if [[ -z ${!inverted:-} ]]; then
    printf -v "$inverted" '%s' "$(key "$1" board.motor pwm_inversed)"
  fi
  if [[ ${!inverted} == true ]]; then [[ $2 == 1000000 ]]; else [[ $2 == 0 ]]; fi
}
# no_torque ROLE: the lever's driver makes no torque, read from the hardware's outputs: its PWM pin gives it no duty
# (pin_inactive), or its enable line (MOTOR_EN, line 0 of its motor chip) is low. Neither the controller's enabled flag nor the
# lever's own telemetry.
no_torque() {
  local enabled period duty polarity applies last pin value=1 gpio=${1}_gpio
  read -r enabled period duty polarity applies last pin <"/sys/devices/platform/lever-pwm-sim.$(pwm_chip "$1")/hw_state" ||
    return 1
  [[ -r ${!gpio}/sim_gpio0/value ]] && read -r value <"${!gpio}/sim_gpio0/value"
  pin_inactive "$1" "$pin" || [[ $value == 0 ]]
}

stop_all() {
  local p
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  wait 2>/dev/null
  collect_results
}

# collect_results: the run's files from the guest's tmpfs to the results share (once)
collect_results() {
  [[ $out == "$results" ]] && return 0
  cp -a "$out/." "$results/" && out=$results
}

# require NAME COMMAND...: check, and on failure stop the test here (the steps after it depend on it), with
# the levers' last status lines and serve's last words for the log
require() {
  local failed_before=$failed
  check "$@"
  ((failed == failed_before)) && return 0
  echo "--- last status: HSI $(tail -n 1 "$out/hsi.stats" 2>/dev/null)" >&2
  echo "--- last status: TOP $(tail -n 1 "$out/top.stats" 2>/dev/null)" >&2
  tail -n 5 "$out"/*.serve >&2
  finish "stopped early"
  exit 1
}
