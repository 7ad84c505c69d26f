# Sourced by the kernel-rig tests that run real lever-fw processes behind `lever-hil serve` (run-in-guest
# --gpio-sim), after lib.sh and gpio_sim_lib.sh. Each lever gets a gpio-sim chip named after its role with the
# lines its config names by default (ENC_A, ENC_B, MOTOR_EN, MOTOR_DIR, MOTOR_FAULT), a PWM tree of the HIL's
# under $pwm/<role>-sys, and a config file $work/<role>.toml.
#
# What the configs change from the example configs, and why. None of it is about the firmware; all of it is
# about an emulated guest (TCG) on a shared two-core machine, where we measured the lever-fw loop's wake-up
# latency at p50 0.3 ms but stalls of up to 190 ms while the host was busy with other work:
# - encoder.counts_per_rev = 2048 (a 512-line encoder) and serve --max-edge-rate 2500: each simulated edge is
#   a sysfs write in the guest, which manages a few thousand a second (at 4096 counts and 5000/s the lines ran
#   538 edges behind), and the kernel keeps 16 events per line (GPIO v1), so lever-fw loses edges when it is
#   held up longer than 32 edges take.
# - board.encoder.edge_latency_us = 1000 (the most the backend takes: an edge waits at most a tick): the guest's
#   interrupt thread delivers an edge's event up to milliseconds
#   after its time stamp; with the board's 50 us, A/B events arrive out of order and count as lost.
# - board.realtime.priority = 0: a SCHED_FIFO loop would starve the gauge's poll thread on the levers' vCPU.
# - board.gauge.poll_us = 20000: each poll costs the guest about a millisecond of CPU; 50 a second leave room.
# - link.comms_timeout_ms, timing.fault_after_ms, gauge.stale_ms = 500 and board.gauge.timeout_us = 200000:
#   a stall of the guest must not look like a dead peer, a late loop, a dead amplifier. The tests still cut
#   links and kill processes, and the levers must then reach their safe states within these.
# Two vCPUs (run-in-guest --smp 2): lever-fw's on vCPU 0, serve and the encoder lines' interrupt threads on
# vCPU 1. There each simulated edge's event reaches its line's FIFO before the next edge is written (the
# interrupt thread, SCHED_FIFO, preempts the writer on its own vCPU), so the A/B order lever-fw reads is the
# order written. Measured on one vCPU for all: 90 % busy, the world fell behind 267 times by over 50 ms in a
# 15 s run, and the TOP's position loop went into a limit cycle on a plant answering that late. Unpinned on two,
# an interrupt thread could wait milliseconds for the other vCPU under TCG: edges out of order, counted lost.
# The PWM trees on tmpfs: lever-fw writes its duty every millisecond and serve reads it back, and /tmp in the
# guest is an overlay on the host's files over 9p, where each of those would be a round trip to the host.
pwm=$(mktemp -d -p /dev/shm)
dbc=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/common/protocol/lever.dbc
dbc_decode=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/tools/dbc-decode
pids=()

lever_chip() {  # lever_chip ROLE: its gpio-sim chip
  sim_chip "$1" ENC_A ENC_B MOTOR_EN MOTOR_DIR MOTOR_FAULT >/dev/null
}

# write_config ROLE CAN_INTERFACE GAUGE_TOML_LINES...: $work/ROLE.toml
write_config() {
  local role=$1 can=$2; shift 2
  {
    printf '[lever]\nrole = "%s"\n[encoder]\ncounts_per_rev = 2048.0\n[timing]\nfault_after_ms = 500\n' "$role"
    printf '[link]\ncomms_timeout_ms = 500\n[gauge]\nstale_ms = 500\n'
    printf '[board.can]\ninterface = "%s"\n[board.encoder]\nchip = "%s"\nedge_latency_us = 1000\n' "$can" "$role"
    printf '[board.motor]\nsysfs_root = "%s"\nline_chip = "%s"\n' "$pwm/$role-sys" "$role"
    printf '[board.realtime]\npriority = 0\n'
    printf '[board.gauge]\ntimeout_us = 200000\npoll_us = 20000\n'
    (($# > 0)) && printf '%s\n' "$@"
  } >"$work/$role.toml"
}

# one_site NAME SERVE_ARGS...: both levers on vcan0 (the TOP's gauge on Modbus TCP), candump logging vcan0 to
# $out/NAME.candump, serve started, then both lever-fw
one_site() {
  local name=$1; shift
  lever_chip hsi && lever_chip top || exit 1
  write_config hsi vcan0
  write_config top vcan0 'transport = "tcp"' 'host = "127.0.0.1"' 'port = 1502'
  candump -r 8388608 -L vcan0 >"$out/$name.candump" &
  pids+=("$!")
  start_serve "$name" "$@" || exit 1
  start_fw hsi
  start_fw top
}

# start_serve NAME ARGS...: lever-hil serve in the background, waiting until its devices are up
start_serve() {
  local name=$1; shift
  taskset -c 1 "$bin/lever-hil" serve --hsi-config "$work/hsi.toml" --top-config "$work/top.toml" --max-edge-rate 2500 "$@" \
    >"$out/$name.report" 2>"$out/$name.serve" &
  serve_pid=$!
  pids+=("$serve_pid")
  for _ in $(seq 600); do
    grep -q "waiting for both" "$out/$name.serve" && return 0
    kill -0 "$serve_pid" 2>/dev/null || break
    sleep 0.1
  done
  echo "FAILED: lever-hil serve did not come up:" >&2
  cat "$out/$name.serve" >&2
  return 1
}

# start_fw ROLE: lever-fw with its status lines in $out/ROLE.stats (appended: a restarted lever goes on)
start_fw() {
  local before=$(irq_threads | wc -l) i
  taskset -c 0 "$bin/lever-fw" --config "$work/$1.toml" --stats-json >>"$out/$1.stats" 2>>"$out/$1.err" &
  eval "${1}_pid=$!"
  pids+=("$!")
  # Its encoder lines' interrupt threads appear when it requests the lines: onto the world's vCPU with them.
  for ((i = 0; i < 100; i++)); do (($(irq_threads | wc -l) >= before + 2)) && break; sleep 0.1; done
  for i in $(irq_threads); do taskset -p 2 "$i" >/dev/null; done
}
irq_threads() { pgrep '^irq/.*-lever-fw'; }

# wait_for_serve NAME TEXT: until serve's log says it (120 s)
wait_for_serve() {
  local deadline=$((SECONDS + 120))
  while ((SECONDS < deadline)); do grep -q "$2" "$out/$1.serve" && return 0; sleep 0.2; done
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
last_stat() { tail -n 1 "$out/$1.stats" 2>/dev/null | jq -r "$2" 2>/dev/null; }

# wait_for SECONDS ROLE JQ_CONDITION: until the lever's newest status line satisfies it
wait_for() {
  local role=$2 condition=$3 deadline=$((SECONDS + $1))
  while ((SECONDS < deadline)); do
    [[ $(last_stat "$role" "$condition") == true ]] && return 0
    sleep 0.2
  done
  echo "timed out after ${1}s waiting for $role: $condition (last: $(tail -n 1 "$out/$role.stats"))" >&2
  return 1
}

# command CAN OPCODE: a command frame to both levers of pair 0 (opcodes: 1 arm, 3 rearm, 6 home), by cansend
command() { cansend "$1" "080#0$2""03000000000000"; }

# A lever's motor as lever-fw left it in the PWM tree: "enable duty_cycle".
pwm_state() { echo "$(head -n 1 "$pwm/$1-sys/class/pwm/pwmchip0/pwm0/enable") $(head -n 1 "$pwm/$1-sys/class/pwm/pwmchip0/pwm0/duty_cycle")"; }

stop_all() {
  local p
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  wait 2>/dev/null
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
