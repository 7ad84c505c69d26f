#!/usr/bin/env bash
# Runs inside the kernel rig in virtual time (run-in-guest --gpio-sim --pwm-sim --virtual-time): lever-view, the live
# view of a pair, as a user runs it, in a terminal (tmux) on vcan0.
#   replay  keeping up: a candump -L log of 1 kHz per lever (a motion and a force frame every millisecond, both
#           heartbeats at 40 Hz) replayed by canplayer while the screen draws at 10 Hz and a second view prints
#           JSON: every frame sent is seen, none dropped, and the rates read 1 kHz
#   pair    a running pair: both lever-fw behind lever-hil serve (one site), homed and armed, then the scenario's
#           end and a disarm; the screen's figures checked against the levers' own status lines; the keys
# usage: lever_view.sh BIN_DIR [replay|pair|all]
set -uo pipefail
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/gpio_sim_lib.sh"
. "$(dirname "$0")/lever_sites_lib.sh"
phase=${2:-all}
case $phase in replay | pair | all) ;; *) echo "lever_view.sh: the second argument must be replay, pair or all (got '$phase')" >&2; exit 2 ;; esac
view=$bin/lever-view
export TMUX_TMPDIR=$work LANG=C.UTF-8
stop_view() { tmux kill-server 2>/dev/null; stop_all; }
trap stop_view EXIT

# screen NAME: the terminal's text now, also kept in $out/NAME.screen (and with its colours in $out/NAME.ansi)
screen() {
  tmux capture-pane -p -t view >"$out/$1.screen"
  tmux capture-pane -p -e -t view >"$out/$1.ansi"
  cat "$out/$1.screen"
}
# start_view ARGS...: lever-view ARGS in a 132x40 terminal; its exit code lands in $out/view.exit
start_view() {
  rm -f "$out/view.exit"
  tmux -u new-session -d -s view -x 132 -y 40 "$(printf '%q ' "$view" "$@"); echo \$? >$out/view.exit" || return 1
}
# screen_until SECONDS TEXT: until the screen shows TEXT
screen_until() {
  local deadline=$((SECONDS + $1))
  while ((SECONDS < deadline)); do [[ $(tmux capture-pane -p -t view) == *"$2"* ]] && return 0; sleep 0.2; done
  echo "timed out waiting for the screen to show '$2':" >&2
  tmux capture-pane -p -t view >&2
  return 1
}
# cpu_ticks PID: the process's user and system time so far, in clock ticks
cpu_ticks() { awk '{ print $14 + $15 }' "/proc/$1/stat"; }
# row TEXT: the screen line that starts with TEXT (after its indent), from the newest capture in $screen_text
row() { grep -m1 -E "^ *$1" <<<"$screen_text"; }
# field LINE WORD: the word after WORD in LINE
field() { awk -v w="$2" '{ for (i = 1; i < NF; i++) if ($i == w) { print $(i + 1); exit } }' <<<"$1"; }

check "a missing interface: exit 2 and a one-line message naming it" \
  bash -c '"$0" --can vcan9 --json >/dev/null 2>"$1/err"; test $? -eq 2 && grep -q "vcan9.*ip link" "$1/err" && test $(wc -l <"$1/err") -eq 1' "$view" "$work"
check "a bad option: exit 2" bash -c '"$0" --can vcan0 --refresh-hz 0 2>/dev/null; test $? -eq 2' "$view"

if [[ $phase == replay || $phase == all ]]; then
  # 5 s at 1 kHz per lever: what the pair sends with the deadband off (p = 0), the most a pair ever sends.
  n=5000
  awk -v n=$n 'function le(v, bytes,   s, k) { s = ""; for (k = 0; k < bytes; k++) { s = s sprintf("%02X", v % 256); v = int(v / 256) } return s }
    BEGIN {
      for (i = 0; i < n; i++) {
        t = 1700000000 + i / 1000
        restart = i == 0 ? 16 : 0
        pos = int(2000 * sin(i / 300)); if (pos < 0) pos += 65536
        vel = int(3000 * cos(i / 300)); if (vel < 0) vel += 65536
        f = int(400000 * (1 + sin(i / 200)))
        printf "(%.6f) vcan0 100#%s%s%s%s%s\n", t, le(pos, 2), le(vel, 2), le(i % 65536, 2), le(i % 256, 1), le(restart, 1)
        printf "(%.6f) vcan0 110#%s%s%s%s00\n", t + 0.0002, le(f, 3), le(i % 65536, 2), le(i % 256, 1), le(restart, 1)
        if (i % 25 == 0) {
          printf "(%.6f) vcan0 700#120000%s0000%s00\n", t + 0.0004, le(i % 256, 1), le(int(i / 25) % 256, 1)
          printf "(%.6f) vcan0 701#120000%s0000%s00\n", t + 0.0006, le(i % 256, 1), le(int(i / 25) % 256, 1)
        }
      }
    }' >"$work/replay.log"
  sent=$(wc -l <"$work/replay.log")
  start_view --can vcan0
  require "the screen comes up" screen_until 20 "no lever frames yet"
  "$view" --can vcan0 --json --refresh-hz 10 >"$out/replay.json" 2>"$out/replay.err" &
  json_pid=$!
  sleep 1
  # candump, independent of lever-view, logs the replay with the kernel's time stamps: the pace canplayer achieved.
  candump -r 8388608 -L vcan0 >"$out/replay.candump" &
  candump_pid=$!
  sleep 0.5
  screen_pid=$(pgrep -P "$(tmux list-panes -t view -F '#{pane_pid}')" -x lever-view)
  cpu_before="$(cpu_ticks "$screen_pid") $(cpu_ticks "$json_pid")"
  canplayer -I "$work/replay.log" &
  player_pid=$!
  sleep 3
  screen_text=$(screen replay-mid)
  drawn=$(field "$(row lever-view)" screen | tr -d '/s')
  # Drawn on a fixed 0.1 s schedule: ten pictures a second over the last ten intervals, the figure printed to 0.1
  # (a screen that draws a period after each picture, not on the schedule, reads 9.9 here and fails).
  check "mid-replay, the screen draws at 10 Hz ($drawn pictures/s) and has seen every frame so far (kernel drops $(field "$(row lever-view)" drops))" \
    test "$(jq -n "$drawn >= 10")/$(field "$(row lever-view)" drops)" = true/0
  wait "$player_pid"
  read -r screen_ticks json_ticks <<<"$(cpu_ticks "$screen_pid") $(cpu_ticks "$json_pid")"
  read -r screen_before json_before <<<"$cpu_before"
  hz=$(getconf CLK_TCK)
  echo "CPU over the 5 s replay (a 1000 MHz virtual core): the screen $(jq -n "($screen_ticks - $screen_before) / $hz") s, --json $(jq -n "($json_ticks - $json_before) / $hz") s"
  sleep 1.5
  kill -TERM "$json_pid" "$candump_pid"; wait "$json_pid"; code=$?
  wait "$candump_pid"
  pace=$(awk '$3 ~ /^100#/ { t = substr($1, 2, length($1) - 2); if (!first) first = t; last = t; n++ }
    END { printf "%.1f", (n - 1) / (last - first) }' "$out/replay.candump")
  echo "canplayer replayed $sent frames (candump logged $(wc -l <"$out/replay.candump")), $pace frames/s per direction"
  check "lever-view --json exits 0 on SIGTERM (got $code)" test "$code" -eq 0
  screen_text=$(screen replay)
  last=$(tail -n 1 "$out/replay.json")
  j() { jq -r "$1" <<<"$last"; }
  echo "JSON view: $(j '{frames: .bus.frames, kernel_drops, motion: .pairs[0].motion.frames, force: .pairs[0].force.frames}' | tr -d '\n ')"
  check "the JSON view saw every frame sent ($(j .bus.frames) of $sent), the kernel dropped none ($(j .kernel_drops))" \
    test "$(j .bus.frames)/$(j .kernel_drops)" = "$sent/0"
  check "all $n motion and $n force frames, none lost or out of order" \
    test "$(j '[.pairs[0].motion.frames, .pairs[0].force.frames, .pairs[0].motion.lost, .pairs[0].force.lost, .pairs[0].motion.out_of_order, .pairs[0].force.out_of_order] | join(" ")')" = "$n $n 0 0 0 0"
  check "every heartbeat, none lost ($(j .pairs[0].hsi.heartbeats) + $(j .pairs[0].top.heartbeats))" \
    test "$(j '[.pairs[0].hsi.heartbeats, .pairs[0].top.heartbeats, .pairs[0].hsi.heartbeats_lost, .pairs[0].top.heartbeats_lost] | join(" ")')" = "$((n / 25)) $((n / 25)) 0 0"
  # Over the last whole second, at the replay's peak: the pace canplayer achieved (its mean over the replay, by
  # candump's time stamps), to within 2 % (the pace is not steady, nor is a second's count exactly its mean).
  rate=$(jq -s -r 'map(.pairs[0].motion.per_s // 0) | max' "$out/replay.json")
  share=$(jq -s -r 'map(.pairs[0].motion.share // 0) | max' "$out/replay.json")
  check "the motion rate at its peak ($rate frames/s, a share of $share of 1 kHz) is canplayer's pace ($pace)" \
    test "$(jq -n "($rate / $pace - 1 | fabs) < 0.02 and ($share - $rate / 1000 | fabs) < 1e-9")" = true
  load=$(jq -s -r 'map(.bus.load) | max' "$out/replay.json")
  # 2 frames per motion frame plus 2 heartbeats per 25, each 135 bits (8 bytes, worst-case stuffing), on 1 Mbit/s.
  check "the bus load at its peak ($load) is that pace's ($pace x 2.08 x 135 bits on 1 Mbit/s)" \
    test "$(jq -n "($load / ($pace * 2.08 * 135 / 1e6) - 1 | fabs) < 0.02")" = true
  intervals=$(jq -s -r '[range(1; length) as $i | .[$i].t - .[$i - 1].t] | max' "$out/replay.json")
  check "the JSON view kept its 10 Hz through the replay (longest interval $intervals s)" \
    test "$(jq -n "$intervals < 0.15")" = true
  echo "$screen_text" | head -n 14
  check "the screen saw every frame as well (frames $(field "$(row lever-view)" frames), kernel drops $(field "$(row lever-view)" drops))" \
    test "$(field "$(row lever-view)" frames)/$(field "$(row lever-view)" drops)" = "$sent/0"
  check "the screen: motion and force, $n frames each, none lost" \
    test "$(field "$(row 'motion HSI>TOP')" frames)/$(field "$(row 'motion HSI>TOP')" lost)/$(field "$(row 'force  TOP>HSI')" frames)/$(field "$(row 'force  TOP>HSI')" lost)" = "$n/0/$n/0"
  tmux send-keys -t view q
  for _ in $(seq 50); do [[ -s $out/view.exit ]] && break; sleep 0.1; done
  check "q quits, exit 0 (got $(cat "$out/view.exit" 2>/dev/null))" test "$(cat "$out/view.exit" 2>/dev/null)" = 0
fi

if [[ $phase == pair || $phase == all ]]; then
  one_site view --duration 5
  up_and_homed
  start_view --can vcan0 --status "$out/hsi.stats" --status "$out/top.stats"
  require "the screen shows both levers disarmed and homed" screen_until 30 "TOP  disarmed    yes"
  command vcan0 1
  require "cansend arm: both arm (serve saw both armed heartbeats)" wait_for_serve view "both levers armed"
  sleep 3
  screen_text=$(screen armed)
  echo "$screen_text"
  hsi_state=$(last_stat hsi .state) top_state=$(last_stat top .state)
  check "armed on the screen as in the status lines (HSI $hsi_state, TOP $top_state), homed, no fault" \
    test "$(row HSI | awk '{ print $2, $3 }')/$(row TOP | awk '{ print $2, $3 }')/$(row HSI | awk '{ print $NF }')/$(row TOP | awk '{ print $NF }')" = "$hsi_state yes/$top_state yes/-/-"
  share=$(row 'motion HSI>TOP' | awk '{ print $4 }')
  saves=$(field "$(row 'motion HSI>TOP')" saves)
  check "the motion share below 1 kHz ($share %), and the deadband's savings its complement ($saves %)" \
    test "$(jq -n "$share > 0 and $share < 90 and ($share + $saves - 100 | fabs) < 0.11")" = true

  wait "$serve_pid"; code=$?
  check "lever-hil serve ran its scenario and exited 0 (got $code)" test "$code" -eq 0
  # The scenario over, the encoders stand still and the pair stays armed. The TOP's lever-fw stopped for 0.3 s
  # (SIGSTOP) latches faults on both levers (the HSI's comms_timeout at least); a disarm then ends the data
  # streams, faults still latched: every count is final.
  kill -STOP "$top_pid"; sleep 0.3; kill -CONT "$top_pid"
  require "a lever latched a fault while the TOP stood still" wait_for 30 hsi '.faults | length > 0'
  command vcan0 2
  require "disarmed (HSI)" wait_for 30 hsi '.state == "disarmed"'
  require "(TOP too)" wait_for 30 top '.state == "disarmed"'
  sleep 1.5  # one more status line each, after the last data frame
  screen_text=$(screen end)
  echo "$screen_text"
  hsi_sent=$(last_stat hsi .data_sent) top_sent=$(last_stat top .data_sent)
  check "every motion frame the HSI sent is on the screen ($hsi_sent), none lost or late" \
    test "$(field "$(row 'motion HSI>TOP')" frames)/$(field "$(row 'motion HSI>TOP')" lost)/$(field "$(row 'motion HSI>TOP')" late)" = "$hsi_sent/0/0"
  check "every force frame the TOP sent ($top_sent), none lost or late" \
    test "$(field "$(row 'force  TOP>HSI')" frames)/$(field "$(row 'force  TOP>HSI')" lost)/$(field "$(row 'force  TOP>HSI')" late)" = "$top_sent/0/0"
  check "no heartbeat lost or late: HSI $(row HSI | awk '{ print $8 }'), TOP $(row TOP | awk '{ print $8 }')" \
    test "$(row HSI | awk '{ print $8 }')/$(row TOP | awk '{ print $8 }')" = "0/0/0/0"
  check "disarmed on the screen as in the status lines" \
    test "$(row HSI | awk '{ print $2 }')/$(row TOP | awk '{ print $2 }')" = "$(last_stat hsi .state)/$(last_stat top .state)"
  for role in hsi top; do
    upper=${role^^}
    shown=$(row "$upper" | awk '{ print $NF }')
    said=$(last_stat $role '.faults | join(",")')
    check "$upper's latched faults by name as its status line says them ($shown; status: ${said:-none})" \
      test "$(tr , '\n' <<<"$shown" | grep -v '^-$' | sort | tr '\n' ' ')" = "$(tr , '\n' <<<"$said" | grep -v '^$' | sort | tr '\n' ' ')"
  done
  # The motion frame carries the position rounded to one encoder count (2 pi/16384 rad); the screen prints four
  # decimals: half a count and half the last digit, 0.00025 rad.
  # (marked ~: the HSI's stream stopped with the disarm)
  shown=$(row HSI | awk '{ print $4 }') said=$(last_stat hsi .position_rad)
  check "the HSI's position on the screen ($shown) is its status line's ($said)" \
    test "$(jq -n "(\"$shown\" | rtrimstr(\"~\") | tonumber) - ($said) | fabs <= 0.00025")" = true
  # The TOP's position is on no frame: the screen shows its status line's, marked.
  shown=$(row TOP | awk '{ print $4 }') said=$(last_stat top .position_rad)
  check "the TOP's position from its status line, marked * ($shown, status $said)" \
    test "$(jq -n "(\"$shown\" | endswith(\"*\")) and ((\"$shown\" | rtrimstr(\"*\") | tonumber) - ($said) | fabs) <= 0.00006")" = true

  tmux send-keys -t view f
  check "f freezes the picture" screen_until 5 "[FROZEN]"
  tmux send-keys -t view r
  require "r resets the counters" screen_until 5 "frames 0"
  screen_text=$(screen reset)
  check "after r: motion and force frames 0, the levers' states kept" \
    test "$(field "$(row 'motion HSI>TOP')" frames)/$(field "$(row 'force  TOP>HSI')" frames)/$(row HSI | awk '{ print $2 }')" = "0/0/disarmed"
  tmux send-keys -t view q
  for _ in $(seq 50); do [[ -s $out/view.exit ]] && break; sleep 0.1; done
  check "q quits, exit 0 (got $(cat "$out/view.exit" 2>/dev/null))" test "$(cat "$out/view.exit" 2>/dev/null)" = 0
fi
finish "lever-view"
