#!/usr/bin/env bash
# lever-fw as a user runs it: help and version, every kind of configuration error (message and exit 2),
# the example configurations, --check-config round trips, the board mode without a board, --motor-off.
# usage: lever_fw_cli.sh path/to/lever-fw path/to/firmware/config
set -uo pipefail
fw=$1
examples=$2
source "$(dirname "$0")/lib.sh"
bad_config() {  # NAME EXPECTED_MESSAGE TOML
  local name=$1 expected=$2
  printf '%s\n' "$3" >"$work/bad.toml"
  "$fw" --config "$work/bad.toml" --check-config >"$work/out" 2>"$work/err"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: names the file and says '$expected' (got: $(cat "$work/err"))" \
    grep -qF -- "$work/bad.toml" "$work/err"
  check "$name: says '$expected'" grep -qF -- "$expected" "$work/err"
  check "$name: prints no configuration" test ! -s "$work/out"
}
taken_config() {  # WHY TOML: a configuration just inside a bound, which must load without a word
  printf '%s\n' "$2" >"$work/edge.toml"
  "$fw" --config "$work/edge.toml" --check-config >/dev/null 2>"$work/err"
  local code=$?
  check "$1, taken: ${2//$'\n'/; } (exit $code: $(head -c 200 "$work/err"))" test "$code" -eq 0 -a ! -s "$work/err"
}

"$fw" --help >"$work/help"; check "--help exits 0" test $? -eq 0
check "--help documents the board's options" grep -q -- "--motor-off" "$work/help"
check "--help documents the exit codes" grep -q "2 bad input" "$work/help"
"$fw" --version >"$work/version"; check "--version exits 0" test $? -eq 0
check "--version names the program" grep -q "lever-fw" "$work/version"
"$fw" >/dev/null 2>"$work/err"; check "no --config: exit 2" test $? -eq 2
# --kernel-check on this machine's kernel: one line naming a model (which one is the machine's), exit 0.
"$fw" --config "$examples/hsi.toml" --kernel-check >"$work/kernel" 2>"$work/err"
check "--kernel-check exits 0 (got $?)" test $? -eq 0
check "--kernel-check says one line naming the model: $(cat "$work/kernel")" \
  grep -qxE "lever-fw: (kernel preemption: (full|PREEMPT_RT) \(.+\)|kernel preemption: not known \(.+|warning: the kernel runs the voluntary preemption model \(.+)" "$work/kernel"
"$fw" --config "$examples/hsi.toml" --kernel-check --motor-off >/dev/null 2>&1
check "--kernel-check with --motor-off: exit 2" test $? -eq 2

: >"$work/empty.toml"
bad_config "unknown key" "codec.motion.q: unknown key" $'[codec.motion]\nq = 0.1'
bad_config "unknown section" "sensor.x: unknown key" $'[sensor]\nx = 1'
bad_config "a table given as an array" "encoder: must be a table ([encoder]), got an array" 'encoder = [1, 2]'
bad_config "a nested table given as a number" "board.encoder: must be a table ([board.encoder]), got an integer" \
  $'[board]\nencoder = 3'
bad_config "a value given as a table" "lever.role: must be a string, got a table" $'[lever.role]\nx = 1'
bad_config "wrong type" "lever.pair: must be a whole number in [0, 15], got a string" $'[lever]\npair = "one"'
bad_config "out of range" "link.comms_timeout_ms: must be a whole number in [1, 60000], got 0" $'[link]\ncomms_timeout_ms = 0'
bad_config "fraction where a whole number belongs" "got 2.5" $'[link]\nheartbeat_ms = 2.5'
bad_config "NaN" "codec.force.p: must be a fraction in [0, 1), got nan" $'[codec.force]\np = nan'
bad_config "infinity" "safety.torque_limit_nm" $'[safety]\ntorque_limit_nm = inf'
bad_config "bad choice" "homing.method: must be one of absolute, hard_stop, index, got 'magnet'" $'[homing]\nmethod = "magnet"'
bad_config "boolean expected" "control.display.closed_loop: must be true or false" $'[control.display]\nclosed_loop = 1'
bad_config "syntax error" "bad.toml:2:" $'[lever]\nrole = '
bad_config "keys that disagree" "must not exceed safety.torque_limit_nm" $'[safety]\ntorque_limit_nm = 0.1\nsafe_hold_torque_nm = 0.2'
bad_config "a low-pass after the passivity port" "control.position.reference_velocity_cutoff_hz, control.passivity.mode: must be 0 on a TOP under tdpa" \
  $'[lever]\nrole = "top"\n[control.position]\nreference_velocity_cutoff_hz = 12.5\n[control.passivity]\nmode = "tdpa"'
taken_config "an HSI has no position loop, so the key does nothing there" \
  $'[control.position]\nreference_velocity_cutoff_hz = 12.5\n[control.passivity]\nmode = "tdpa"'
# Relations that make a fault certain at rest (issue 40, item 5), each at its edge, and the value just past it taken.
bad_config "COMMS certain at rest" "link.comms_timeout_ms: 25 ms is not longer than the gap between the peer's frames at rest (25 ms" \
  $'[link]\ncomms_timeout_ms = 25'
bad_config "COMMS certain at rest, the refresh the shorter gap" "link.comms_timeout_ms: 40 ms is not longer than the gap between the peer's frames at rest (40 ms" \
  $'[link]\nheartbeat_ms = 50\nrefresh_ms = 40\ncomms_timeout_ms = 40'
bad_config "homing that must time out" "homing.timeout_ms: 100 ms is not longer than homing.stall_ms (100 ms)" \
  $'[homing]\ntimeout_ms = 100'
bad_config "POSITION_LIMIT certain once homed" "homing.home_position_rad: -1.01 rad is outside safety.position_min_rad..position_max_rad (-1 to" \
  $'[homing]\nhome_position_rad = -1.01'
for relation in $'[link]\ncomms_timeout_ms = 26' $'[homing]\ntimeout_ms = 101' $'[homing]\nhome_position_rad = -1.0' \
  $'[homing]\nmethod = "absolute"\nhome_position_rad = -1.01'; do
  taken_config "just inside the relation" "$relation"
done
# The velocity estimate's 1 ms Euler step is stable below b T = 2 sqrt(2) - 2 (828.4 rad/s): 828 taken, 829 refused.
bad_config "a velocity estimate past its stability limit" "velocity.bandwidth_rad_s: must be a number of rad/s in [1, 828], got 829" \
  $'[velocity]\nbandwidth_rad_s = 829'
taken_config "the velocity estimate at its limit" $'[velocity]\nbandwidth_rad_s = 828'
bad_config "a gauge staler than its polls" "gauge.stale_ms: 5 ms does not outlast one missed poll" $'[gauge]\nstale_ms = 5\n[board.gauge]\npoll_us = 10000'
# The gauge's timings as a relation: one missed poll costs a response timeout, RTU's a backoff more.
bad_config "a stale window one missed poll reaches" \
  "a reading may be 35.0 ms old (poll_us + 2 x timeout_us + timeout_us for the reconnect); at least 36 ms" \
  $'[gauge]\nstale_ms = 35'
bad_config "a longer timeout alone" "a reading may be 65.0 ms old" $'[board.gauge]\ntimeout_us = 20000'
bad_config "RTU with a longer backoff" "(poll_us + 2 x timeout_us + reconnect_backoff_ms); at least 76 ms" \
  $'[board.gauge]\ntransport = "rtu"\nreconnect_backoff_ms = 50'
printf '[gauge]\nstale_ms = 76\n[board.gauge]\ntransport = "rtu"\nreconnect_backoff_ms = 50\n' >"$work/rtu.toml"
"$fw" --config "$work/rtu.toml" --check-config >/dev/null 2>"$work/err"
check "RTU with a window that outlasts one missed poll: valid ($(cat "$work/err"))" test $? -eq 0
bad_config "a saturation bound the register never reaches" "saturation would never be seen" \
  $'[board.gauge]\nsaturation_raw_max = 1e15'
bad_config "a prefilter above Nyquist" "codec.motion.filter_hz" $'[codec.motion]\nfilter_hz = 800'
# The codec's keys take what lever-ctl set-deadband's options take (codec_cli's kOnWire), in the options' words.
bad_config "a prefilter at Nyquist" \
  "codec.motion.filter_hz: must be a cut-off in Hz below Nyquist (500 Hz at 1 kHz) in [0, 500), got 500" \
  $'[codec.motion]\nfilter_hz = 500'
bad_config "a Weber fraction above 1" "codec.force.p: must be a fraction in [0, 1), got 1.5" $'[codec.force]\np = 1.5'
bad_config "a Weber fraction of 1 (no change ever perceived)" "codec.motion.p: must be a fraction in [0, 1), got 1" \
  $'[codec.motion]\np = 1'
bad_config "a floor the CAN frame cannot carry" "codec.force.floor: must be a floor in N in [0, 65.535], got 65.536" \
  $'[codec.force]\nfloor = 65.536'
for inside in $'[codec.motion]\nfilter_hz = 499.9' $'[codec.force]\np = 0.9999' $'[codec.force]\nfloor = 65.535'; do
  taken_config "just inside the codec's range" "$inside"
done
"$fw" --config "$work/missing.toml" --check-config 2>"$work/err"; code=$?
check "missing file: exit 2" test "$code" -eq 2
check "missing file: says why" grep -q "missing.toml: cannot read: No such file" "$work/err"

# A configuration given as any kind of file: only a regular file is read, and nothing hangs.
mkdir "$work/adir"; mkfifo "$work/afifo"
head -c $((1024 * 1024 + 1)) /dev/zero | tr '\0' '#' >"$work/huge.toml"
for kind in "$work/adir:a directory, not a configuration file" "$work/afifo:a FIFO, not a configuration file" \
  "/dev/null:a device, not a configuration file" "$work/huge.toml:1048577 bytes; a configuration file is at most 1048576"; do
  path=${kind%%:*} says=${kind#*:}
  timeout 10 "$fw" --config "$path" --check-config >"$work/out" 2>"$work/err"; code=$?
  check "config $path: exit 2, at once (got $code)" test "$code" -eq 2
  check "config $path: says '$says' (got: $(cat "$work/err"))" grep -qF -- "$path: $says" "$work/err"
  check "config $path: prints no configuration" test ! -s "$work/out"
done
bad_config "an integer too large for TOML" "bad.toml:2:" $'[link]\ncomms_timeout_ms = 99999999999999999999999'
bad_config "a huge number" "link.comms_timeout_ms: must be a whole number in [1, 60000], got 1e+300" $'[link]\ncomms_timeout_ms = 1e300'
bad_config "a huge string" "board.can: interface" "$(printf '[board.can]\ninterface = "%s"' "$(head -c 100000 /dev/zero | tr '\0' a)")"
# Interface names as the kernel takes them, in the file and on the command line alike.
for name in "can/0" "can:0" "can 0" "." ".." "can%d" "sixteen-bytes-xx" ""; do
  bad_config "interface name '$name'" "board.can: interface" "$(printf '[board.can]\ninterface = "%s"' "$name")"
  "$fw" --config "$work/empty.toml" --can "$name" --check-config >"$work/out" 2>"$work/err"; code=$?
  check "--can '$name': exit 2 like the same name in the file (got $code)" test "$code" -eq 2
  check "--can '$name': names the option (got: $(cat "$work/err"))" grep -qF -- "--can: board.can.interface" "$work/err"
done
for name in "can0" "fifteen-bytes-x" "..." "vcan-ä"; do
  "$fw" --config "$work/empty.toml" --can "$name" --check-config >"$work/out" 2>"$work/err"; code=$?
  check "--can '$name', a name the kernel allows: exit 0 (got $code: $(cat "$work/err"))" test "$code" -eq 0
  check "--can '$name' is the effective interface" grep -qF -e "interface = '$name'" -e "interface = \"$name\"" "$work/out"
done

"$fw" --config "$examples/top-float32.toml" --check-config >"$work/f32"; code=$?
check "example top-float32.toml is valid" test "$code" -eq 0
check "example top-float32.toml reads a float32 from input registers" \
  grep -qE '^(function = "input"|type = "float32")' "$work/f32"
bad_config "a Modbus amplifier's host that is a name, not an address" "board.gauge" $'[board.gauge]\nhost = "amplifier.local"'
bad_config "a baud rate that is not standard" "board.gauge" $'[board.gauge]\ntransport = "rtu"\nbaud = 12345'
for role in hsi top; do
  "$fw" --config "$examples/$role.toml" --check-config >"$work/$role.out"; code=$?
  check "example $role.toml is valid" test "$code" -eq 0
  grep -v '^#' "$work/$role.out" >"$work/$role.toml"
  "$fw" --config "$work/$role.toml" --check-config | grep -v '^#' >"$work/$role.again"
  check "example $role.toml: the printed configuration loads back to itself" cmp -s "$work/$role.toml" "$work/$role.again"
  check "example $role.toml: role $role" grep -q "^role = \"$role\"" "$work/$role.toml"
done
# The examples list every key at its default as the program prints it, help included (docs/lever-fw.md).
for example in hsi top top-float32; do
  "$fw" --config "$examples/$example.toml" --check-config | grep -v -e '^#' -e '^$' >"$work/printed"
  grep -v -e '^#' -e '^$' "$examples/$example.toml" >"$work/example"
  check "example $example.toml is what --check-config prints ($(diff "$work/example" "$work/printed" | head -c 300))" \
    cmp -s "$work/example" "$work/printed"
done
# --get KEY: one key's effective value, as the shell tests read a configuration (no TOML parsing of their own).
check "--get a number" test "$("$fw" --config "$examples/top.toml" --get control.position.kp_nm_per_rad)" = 40.0
check "--get a string, bare" test "$("$fw" --config "$examples/top.toml" --get lever.role)" = top
check "--get a key the file leaves out: its default" \
  test "$("$fw" --config "$work/empty.toml" --role hsi --get link.heartbeat_ms)" = 25
check "--get an empty string: an empty line" test "$("$fw" --config "$examples/top.toml" --get board.watchdog.device)" = ""
getset_bad() {  # NAME EXPECTED_MESSAGE ARGS...
  local name=$1 expected=$2; shift 2
  "$fw" --config "$examples/top.toml" "$@" >"$work/out" 2>"$work/err"
  local code=$?
  check "$name: exit code 2 (got $code)" test "$code" -eq 2
  check "$name: says '$expected' (got: $(cat "$work/err"))" grep -qF -- "$expected" "$work/err"
  check "$name: prints nothing on stdout" test ! -s "$work/out"
}
getset_bad "--get an unknown key" "--get: no key 'control.position.kq'" --get control.position.kq
getset_bad "--get with --check-config" "excludes" --get lever.role --check-config
# --set KEY=VALUE: a key overridden after the file, checked as in the file, in order; --role and --can after it.
check "--set a number" test "$("$fw" --config "$examples/top.toml" --set codec.motion.p=0.05 --get codec.motion.p)" = 0.05
check "--set twice: the last wins" \
  test "$("$fw" --config "$examples/top.toml" --set codec.motion.p=0.05 --set codec.motion.p=0.07 --get codec.motion.p)" = 0.07
check "--set a string" \
  test "$("$fw" --config "$examples/top.toml" --set 'board.can.interface="vcan3"' --get board.can.interface)" = vcan3
check "--can after --set" \
  test "$("$fw" --config "$examples/top.toml" --set 'board.can.interface="vcan3"' --can vcan4 --get board.can.interface)" = vcan4
"$fw" --config "$examples/top.toml" --set board.motor.pwm_chip=3 --check-config >"$work/set.toml"
check "--set then --check-config: a configuration that loads back with the key set" \
  test "$("$fw" --config "$work/set.toml" --get board.motor.pwm_chip)" = 3
getset_bad "--set out of range" "--set: link.comms_timeout_ms: must be a whole number in [1, 60000], got 0" \
  --set link.comms_timeout_ms=0 --check-config
getset_bad "--set a string without its quotes" "is no TOML value (a string needs its quotes" \
  --set board.can.interface=vcan3 --check-config
getset_bad "--set an unknown key" "--set: codec.motion.q: unknown key" --set codec.motion.q=1 --check-config
getset_bad "--set a Weber fraction above 1" "--set: codec.motion.p: must be a fraction in [0, 1), got 1.5" \
  --set codec.motion.p=1.5 --check-config
getset_bad "--set a prefilter at Nyquist" "--set: codec.force.filter_hz: must be a cut-off in Hz below Nyquist" \
  --set codec.force.filter_hz=500 --check-config
getset_bad "--set without =" "expected KEY=VALUE" --set codec.motion.p --check-config
getset_bad "--set with --motor-off, which reads the file's motor keys alone" "excludes" \
  --set board.motor.pwm_chip=1 --motor-off
getset_bad "--set a wrong type" "--set: lever.pair: must be a whole number" --set 'lever.pair="one"' --check-config
# The examples are every key at its default: they cannot drift from the program.
for role in hsi top; do
  "$fw" --config "$work/empty.toml" --role "$role" --check-config | sed 1d >"$work/defaults.$role"
  sed '/^#/d' "$examples/$role.toml" | sed '1{/^$/d}' >"$work/example.$role"
  check "example $role.toml lists every key at its default" cmp -s "$work/defaults.$role" "$work/example.$role"
done
# The timing budget and its window are named values of the effective configuration (docs/firmware.md).
"$fw" --config "$work/empty.toml" --check-config >"$work/timing"
check "--check-config prints the timing budget" grep -qx 'fault_after_ms = 2 .*' "$work/timing"
check "--check-config prints the budget's window" grep -q '^window_ms = 68 ' "$work/timing"
check "--check-config prints the long-step threshold" grep -q '^long_step_us = 100 ' "$work/timing"
"$fw" --config "$examples/hsi.toml" --role top --check-config >"$work/override"
check "--role overrides the file" grep -q '^role = "top"' "$work/override"

# On a machine without the board's hardware: a runtime failure naming what could not be opened, no hang. The motor
# is opened first, and its guard started with it (docs/board-motor.md, "The motor guard").
printf '[board.motor]\nsysfs_root = "%s"\n' "$work/no-such-sys" >"$work/nopwm.toml"
timeout 20 "$fw" --config "$work/nopwm.toml" 2>"$work/err"; code=$?
check "without the board's PWM: exit 1 (got $code)" test "$code" -eq 1
check "and names the motor and the PWM chip" grep -q "cannot open the motor.*pwmchip0" "$work/err"
guard_tree=$work/guard-sys/class/pwm/pwmchip0
mkdir -p "$guard_tree/pwm0" && : >"$guard_tree/export"
printf '0\n' >"$guard_tree/pwm0/enable"; printf '0\n' >"$guard_tree/pwm0/duty_cycle"
printf '50000\n' >"$guard_tree/pwm0/period"; printf 'normal\n' >"$guard_tree/pwm0/polarity"
printf '[board.encoder]\nchip = "/dev/no-such-gpiochip"\n[board.motor]\nsysfs_root = "%s"\n%s\n' "$work/guard-sys" \
  'enable_line = ""
direction_line = ""
fault_line = ""' >"$work/nochip.toml"
timeout 20 "$fw" --config "$work/nochip.toml" 2>"$work/err"; code=$?
check "without the board's GPIO chip: exit 1 (got $code)" test "$code" -eq 1
check "and names the encoder and the chip" grep -q "cannot open the encoder.*no-such-gpiochip" "$work/err"
check "after its motor guard had started" grep -q "motor guard pid [0-9]*: deadline" "$work/err"
check "which stopped the motor when lever-fw ended" grep -q "motor guard: the lever (pid [0-9]*) ended: motor off" "$work/err"

# --motor-off (the service's ExecStopPost=): a PWM channel left running by a lever-fw that died is stopped. Outside
# a unit unless a case says otherwise: a unit's runs are told apart by $INVOCATION_ID.
unset INVOCATION_ID
pwm=$work/sys/class/pwm/pwmchip0
mkdir -p "$pwm/pwm0" && : >"$pwm/export"
printf '1\n' >"$pwm/pwm0/enable"; printf '25000\n' >"$pwm/pwm0/duty_cycle"
printf '50000\n' >"$pwm/pwm0/period"; printf 'normal\n' >"$pwm/pwm0/polarity"
# The keys that name the motor's hardware, each given: --motor-off never takes a default for one.
motor_keys='pwm_chip = 0\npwm_channel = 0\nenable_line = ""\ndirection_line = ""\nfault_line = ""\n'
printf "[board.motor]\nsysfs_root = \"%s\"\n$motor_keys" "$work/sys" >"$work/motor.toml"
timeout 20 "$fw" --config "$work/motor.toml" --motor-off 2>"$work/err"; code=$?
check "--motor-off: exit 0 (got $code: $(cat "$work/err"))" test "$code" -eq 0
# Stopped is duty 0 with the PWM left enabled: a disabled PWM's output is undefined (docs/board-motor.md).
check "--motor-off: at duty 0" test "$(head -n1 "$pwm/pwm0/duty_cycle")" = 0
check "--motor-off: the PWM left enabled (at duty 0: its inactive level)" test "$(head -n1 "$pwm/pwm0/enable")" = 1
# Bounded in time whatever is under its sysfs root: FIFOs, directories and loops where attributes belong.
for case in fifo-enable fifo-export dir-duty loop-period; do
  root=$work/sys-$case chip=$work/sys-$case/class/pwm/pwmchip0
  mkdir -p "$chip/pwm0"
  for f in enable duty_cycle period polarity; do printf '0\n' >"$chip/pwm0/$f"; done
  : >"$chip/export"
  case $case in
    fifo-enable) rm "$chip/pwm0/enable"; mkfifo "$chip/pwm0/enable" ;;
    fifo-export) rm -r "$chip/pwm0" "$chip/export"; mkfifo "$chip/export" ;;
    dir-duty) rm "$chip/pwm0/duty_cycle"; mkdir "$chip/pwm0/duty_cycle" ;;
    loop-period) rm "$chip/pwm0/period"; ln -s period "$chip/pwm0/period" ;;
  esac
  printf "[board.motor]\nsysfs_root = \"%s\"\n$motor_keys" "$root" >"$work/m.toml"
  start=$(date +%s%N)
  timeout 20 "$fw" --config "$work/m.toml" --motor-off 2>"$work/err"; code=$?
  elapsed_ms=$((($(date +%s%N) - start) / 1000000))
  check "--motor-off on $case: exit 1 (got $code: $(cat "$work/err"))" test "$code" -eq 1
  check "--motor-off on $case: done within 3 s (export_timeout_ms 1000 and a few writes; took $elapsed_ms ms)" \
    test "$elapsed_ms" -lt 3000
  check "--motor-off on $case: names the file" grep -q "motor-off: cannot stop the motor .*: motor PWM: .*$root" "$work/err"
done
printf "[board.motor]\nsysfs_root = \"%s\"\n$motor_keys" "$work/no-such-sys" >"$work/nomotor.toml"
timeout 20 "$fw" --config "$work/nomotor.toml" --motor-off 2>"$work/err"; code=$?
check "--motor-off without the PWM: exit 1 (got $code)" test "$code" -eq 1
check "--motor-off without the PWM: names it" grep -q "motor-off: cannot stop the motor.*no-such-sys" "$work/err"

# --motor-off reads the motor's keys alone: a configuration that no longer validates (edited under the running
# lever, a key another version refuses) still stops the motor, and says what else is wrong. When even the motor's
# keys cannot be read, the motor state the lever wrote at start (--motor-state) names the motor.
running() { printf '1\n' >"$pwm/pwm0/enable"; printf '30000\n' >"$pwm/pwm0/duty_cycle"; }
stopped() { [[ $(head -n1 "$pwm/pwm0/enable") == 1 && $(head -n1 "$pwm/pwm0/duty_cycle") == 0 ]]; }
motor_off_case() {  # NAME EXPECTED_CODE SAYS CONFIG [--motor-state FILE]: --motor-off on a running motor
  local name=$1 expected=$2 says=$3 config=$4; shift 4
  running
  timeout 20 "$fw" --config "$config" --motor-off "$@" 2>"$work/err"; code=$?
  check "--motor-off, $name: exit $expected (got $code: $(tr '\n' '|' <"$work/err"))" test "$code" -eq "$expected"
  if ((expected == 0)); then
    check "--motor-off, $name: the motor is stopped (duty 0, enable 1)" stopped
  else
    check "--motor-off, $name: the motor was left as it was (duty 30000)" test "$(head -n1 "$pwm/pwm0/duty_cycle")" = 30000
  fi
  check "--motor-off, $name: says '$says'" grep -qF -- "$says" "$work/err"
}
{ cat "$work/motor.toml"; printf '[encoder]\ncounts_per_rev = 0.5\n'; } >"$work/bad-encoder.toml"
motor_off_case "wrong encoder range" 0 "encoder.counts_per_rev: must be" "$work/bad-encoder.toml"
{ cat "$work/motor.toml"; printf '[board.gauge]\nscale_factor = 2.0\n'; } >"$work/bad-gauge-key.toml"
motor_off_case "unknown gauge key" 0 "board.gauge.scale_factor: unknown key" "$work/bad-gauge-key.toml"
{ cat "$work/motor.toml"; printf '[gauge]\nstale_ms = 2\n'; } >"$work/bad-gauge-timing.toml"
motor_off_case "gauge timing relation broken" 0 "gauge.stale_ms: 2 ms does not outlast one missed poll" \
  "$work/bad-gauge-timing.toml"
{ cat "$work/motor.toml"; printf '[safety]\nposition_min_rad = 1.0\nposition_max_rad = -1.0\n'; } >"$work/bad-range.toml"
motor_off_case "safety range inverted" 0 "the minimum must be below the maximum" "$work/bad-range.toml"
# The motor state: written by a lever-fw at start, before anything is opened (here it then fails at the encoder).
{ cat "$work/motor.toml"; printf '[board.encoder]\nchip = "/dev/no-such-gpiochip"\n'; } >"$work/run.toml"
timeout 20 "$fw" --config "$work/run.toml" --motor-state "$work/run/motor" 2>"$work/err"; code=$?
check "a lever-fw that cannot write its motor state does not start: exit 1 (got $code)" test "$code" -eq 1
check "and says so" grep -qF "the motor state for --motor-off: cannot write $work/run/motor" "$work/err"
mkdir -p "$work/run"
timeout 20 "$fw" --config "$work/run.toml" --motor-state "$work/run/motor" 2>"$work/err"; code=$?
check "a lever-fw that fails at its encoder has written its motor state first (exit $code)" test -s "$work/run/motor"
cp "$work/run.toml" "$work/cut.toml" && truncate -s "$(($(stat -c %s "$work/run.toml") / 2))" "$work/cut.toml"
motor_off_case "file cut in half, no motor state" 1 "the motor is NOT stopped" "$work/cut.toml"
motor_off_case "file cut in half" 0 "(named by the motor state $work/run/motor)" "$work/cut.toml" \
  --motor-state "$work/run/motor"
motor_off_case "file gone" 0 "(named by the motor state $work/run/motor)" "$work/no-such.toml" \
  --motor-state "$work/run/motor"
{ cat "$work/motor.toml"; printf 'max_duty = 7\n'; } >"$work/bad-motor.toml"  # in [board.motor]
motor_off_case "a motor key out of range" 0 "(named by the motor state $work/run/motor)" "$work/bad-motor.toml" \
  --motor-state "$work/run/motor"
motor_off_case "a motor key out of range, no motor state" 1 "board.motor.max_duty: must be" "$work/bad-motor.toml"
# Cut short at a line's end, the file is valid TOML without its [board.motor] keys: their defaults would name
# another motor (pwmchip0 under /sys here). With a state, the state's motor is the one stopped.
{ printf '[board.encoder]\nchip = "/dev/no-such-gpiochip"\n'; cat "$work/motor.toml"; } | sed '/^\[board.motor\]/,$d' \
  >"$work/short.toml"
motor_off_case "file cut short at a line's end (valid TOML, no motor keys)" 0 \
  "(named by the motor state $work/run/motor)" "$work/short.toml" --motor-state "$work/run/motor"
# Edited under the running lever to name another channel: the one it ran (its state) stops; the configuration's
# new one is not this lever's motor yet, and is left alone (on a machine of two levers it may be the other's).
mkdir -p "$pwm/pwm1" && for f in enable duty_cycle period polarity; do cp "$pwm/pwm0/$f" "$pwm/pwm1/$f"; done
sed -n '/^\[board.motor\]/,$p' "$work/run/motor" | sed 's/^pwm_channel = 0/pwm_channel = 1/' >"$work/other.toml"
printf '1\n' >"$pwm/pwm1/enable"; printf '30000\n' >"$pwm/pwm1/duty_cycle"
motor_off_case "the configuration names another channel than the state" 0 \
  "the configuration names another motor than the one this lever ran" "$work/other.toml" --motor-state "$work/run/motor"
check "--motor-off, another channel: the state's stopped, the configuration's left running" \
  test "$(head -n1 "$pwm/pwm1/duty_cycle")" = 30000
# The motor named explicitly or not at all: a key left out is its default, and the defaults name a motor too
# (pwmchip0/pwm0; here under the test's sysfs root, on a board maybe another lever's). Each case below must leave
# the running motor's tree exactly as it was (every file under $work/sys), exit as said, and say why.
tree_sum() { find "$work/sys" -type f -print0 | sort -z | xargs -0 cat | md5sum; }
untouched_case() {  # NAME EXPECTED_CODE SAYS INVOCATION_ID CONFIG [ARGS...]: --motor-off that must stop nothing
  local name=$1 expected=$2 says=$3 invocation=$4 config=$5; shift 5
  running
  local before; before=$(tree_sum)
  INVOCATION_ID=$invocation timeout 20 "$fw" --config "$config" --motor-off "$@" 2>"$work/err"; code=$?
  check "--motor-off, $name: exit $expected (got $code: $(tr '\n' '|' <"$work/err"))" test "$code" -eq "$expected"
  check "--motor-off, $name: the PWM tree is untouched (enable $(head -n1 "$pwm/pwm0/enable"))" \
    test "$(tree_sum)" = "$before"
  check "--motor-off, $name: says '$says'" grep -qF -- "$says" "$work/err"
  if ((expected == 1)); then check "--motor-off, $name: says the motor is NOT stopped" grep -qF "NOT stopped" "$work/err"; fi
}
printf '[board.motor]\nsysfs_root = "%s"\n[board.moter]\npwm_chip = 0\npwm_channel = 0\nenable_line = ""\n' "$work/sys" \
  >"$work/typo.toml"
untouched_case "the motor's keys under a misspelt [board.moter]" 1 \
  "board.motor.pwm_chip, board.motor.pwm_channel, board.motor.enable_line, board.motor.direction_line, board.motor.fault_line, board.motor.line_chip: missing" \
  "" "$work/typo.toml"
check "--motor-off, [board.moter]: names the misspelt keys" grep -qF "board.moter.pwm_chip: unknown key" "$work/err"
untouched_case "an empty configuration" 1 "board.motor.pwm_chip, board.motor.pwm_channel" "" "$work/empty.toml"
printf '[board.motor]\nsysfs_root = "%s"\n' "$work/sys" >"$work/root-only.toml"
untouched_case "a configuration with the sysfs root alone" 1 \
  "the configuration's motor keys do not name a motor, and no --motor-state" "" "$work/root-only.toml"
printf '[board.motor]\nsysfs_root = "%s"\npwm_chip = 0\npwm_channel = 0\nenable_line = "3"\ndirection_line = ""\nfault_line = ""\n' \
  "$work/sys" >"$work/no-line-chip.toml"
untouched_case "an enable line without its chip" 1 "board.motor.line_chip: missing" "" "$work/no-line-chip.toml"

# A state names the motor whole or not at all: beside a valid configuration, an empty or cut one stops nothing
# (neither the defaults' motor nor the configuration's, which the lever may never have opened).
mkdir -p "$work/states"
: >"$work/states/empty"
untouched_case "an empty state beside a valid configuration" 1 "board.motor.sysfs_root, board.motor.pwm_chip" "" \
  "$work/motor.toml" --motor-state "$work/states/empty"
check "--motor-off, an empty state: says it names no motor" grep -qF "names no motor" "$work/err"
sed '/^pwm_chip = /,$d' "$work/run/motor" >"$work/states/cut-at-line"  # valid TOML up to the sysfs root
untouched_case "a state cut at a line's end (the sysfs root kept)" 1 "board.motor.pwm_chip, board.motor.pwm_channel" "" \
  "$work/motor.toml" --motor-state "$work/states/cut-at-line"
head -c "$(($(stat -c %s "$work/run/motor") / 2))" "$work/run/motor" >"$work/states/cut-half"
untouched_case "a state cut in half" 1 "names no motor" "" "$work/motor.toml" --motor-state "$work/states/cut-half"
# Short of its last key only (the lines' polarity, which says which level is off): not whole, so not the lever's.
sed '/^lines_active_low = /d' "$work/run/motor" >"$work/states/no-polarity"
untouched_case "a state short of its last key" 1 "board.motor.lines_active_low: missing" "" "$work/motor.toml" \
  --motor-state "$work/states/no-polarity"
sed '/^\[writer\]/,/^pid = /d' "$work/run/motor" >"$work/states/no-writer"
untouched_case "a state without its writer" 1 "writer.invocation_id, writer.boot_id, writer.pid: missing" "" \
  "$work/motor.toml" --motor-state "$work/states/no-writer"
untouched_case "no state outside a unit" 1 "no motor state $work/states/none" "" "$work/motor.toml" \
  --motor-state "$work/states/none"
if [[ -r /proc/sys/kernel/random/boot_id ]]; then
  sed 's/^boot_id = .*/boot_id = "00000000-0000-0000-0000-000000000000"/' "$work/run/motor" >"$work/states/other-boot"
  untouched_case "a state of another boot" 1 "is STALE: written by pid" "" "$work/motor.toml" \
    --motor-state "$work/states/other-boot"
fi

# Under the unit ($INVOCATION_ID, the same for ExecStart and ExecStopPost): a state of this invocation only.
# RuntimeDirectoryPreserve=restart keeps an earlier run's; a run that died before its state was written opened
# nothing, so --motor-off says so and exits 0, and never falls back to the configuration's motor.
unit_a=0123456789abcdef0123456789abcdef unit_b=fedcba9876543210fedcba9876543210
mkdir -p "$work/unit"
INVOCATION_ID=$unit_a timeout 20 "$fw" --config "$work/run.toml" --motor-state "$work/unit/motor" 2>"$work/err"
check "a lever-fw under a unit names its invocation in the state" grep -qE "^invocation_id = [\"']$unit_a[\"'] " "$work/unit/motor"
check "and its pid" grep -qx 'pid = [1-9][0-9]*' "$work/unit/motor"
untouched_case "a state of another invocation of the unit" 1 \
  "is STALE: written by another run (pid" "$unit_b" "$work/motor.toml" --motor-state "$work/unit/motor"
check "--motor-off, another invocation: names both" grep -qF "invocation $unit_a), not this one (invocation $unit_b)" "$work/err"
untouched_case "no state under the unit (the run died before it opened anything)" 0 \
  "nothing to stop: this run (invocation $unit_b) wrote no motor state $work/unit/none" "$unit_b" \
  "$work/motor.toml" --motor-state "$work/unit/none"
running
INVOCATION_ID=$unit_a timeout 20 "$fw" --config "$work/motor.toml" --motor-state "$work/unit/motor" --motor-off \
  2>"$work/err"; code=$?
check "--motor-off, the state of this invocation: exit 0 (got $code: $(tr '\n' '|' <"$work/err"))" test "$code" -eq 0
check "--motor-off, the state of this invocation: the motor is stopped" stopped
check "--motor-off, the state of this invocation: named by it" grep -qF "(named by the motor state $work/unit/motor)" "$work/err"
"$fw" --config "$work/motor.toml" --motor-off --check-config 2>/dev/null; code=$?
check "--motor-off with --check-config: exit 2 (got $code)" test "$code" -eq 2
"$fw" --config "$examples/top.toml" --sim 2>/dev/null; code=$?
check "the simulator is not in lever-fw: --sim is bad input, exit 2 (got $code)" test "$code" -eq 2

report "lever-fw cli"
