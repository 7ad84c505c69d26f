#!/usr/bin/env bash
# tools/dbc-decode as a user runs it, and on garbage: help and version, the exit codes and one-line messages of
# docs/bad-input.md for every kind of bad DBC and log, never a traceback, never a hang.
# usage: dbc_decode_cli.sh path/to/tools/dbc-decode path/to/lever.dbc
set -uo pipefail
decode=$1
dbc=$2
source "$(dirname "$0")/lib.sh"
run() {  # run ARGS...: never more than 10 s; sets code, output in $work/out and $work/err
  timeout 10 "$decode" "$@" >"$work/out" 2>"$work/err" </dev/null
  code=$?
}
expect() {  # expect CODE NAME EXPECTED_MESSAGE ARGS...
  local want=$1 name=$2 expected=$3; shift 3
  run "$@"
  check "$name: exit code $want (got $code)" test "$code" -eq "$want"
  check "$name: says '$expected' (got: $(head -c 300 "$work/err"))" grep -qF -- "$expected" "$work/err"
  check "$name: no traceback" bash -c "! grep -q Traceback '$work/err'"
  # 20 lines named, one count of the rest, one of the lines skipped
  check "$name: at most 22 lines of messages (got $(wc -l <"$work/err"))" test "$(wc -l <"$work/err")" -le 22
}

run --help; check "--help exits 0" test "$code" -eq 0
check "--help documents the exit codes" grep -q "Exit codes" "$work/out"
run --version; check "--version exits 0" test "$code" -eq 0
check "--version names the program" grep -q "dbc-decode" "$work/out"
expect 2 "no arguments" "usage: dbc-decode"
expect 2 "an unknown option" "unknown option '--frobnicate'" --frobnicate "$dbc"

# The DBC: only a regular file of UTF-8 text, in the subset this decoder reads.
mkdir "$work/adir"; mkfifo "$work/afifo"
expect 2 "a missing DBC" "cannot read: No such file" "$work/none.dbc"
expect 2 "a DBC that is a directory" "a directory, not a DBC file" "$work/adir"
expect 2 "a DBC that is a device" "a device, not a DBC file" /dev/zero
expect 2 "a DBC that is a FIFO" "a FIFO, not a DBC file" "$work/afifo"
head -c 4096 /dev/urandom >"$work/random.dbc"
expect 2 "a DBC of random bytes" "$work/random.dbc: " "$work/random.dbc"
printf 'hello\nworld\n' >"$work/text.dbc"
expect 2 "a DBC of text without messages" "no messages (BO_ lines); not a DBC file" "$work/text.dbc"
head -c $((1024 * 1024 + 1)) /dev/zero | tr '\0' ' ' >"$work/huge.dbc"
expect 2 "a DBC over 1 MiB" "a DBC file is at most that" "$work/huge.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ S : 0|16@1+ (abc,0) [0|0] "" Node\n' >"$work/factor.dbc"
expect 2 "a factor that is no number" "factor 'abc' is not a number" "$work/factor.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ S : 0|16@1+ (1e400,0) [0|0] "" Node\n' >"$work/inf.dbc"
expect 2 "a factor that is infinite" "is not finite" "$work/inf.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ S : 60|16@1+ (1,0) [0|0] "" Node\n' >"$work/wide.dbc"
expect 2 "a signal beyond the frame" "does not fit in 8 bytes" "$work/wide.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ S : 0|0@1+ (1,0) [0|0] "" Node\n' >"$work/empty-signal.dbc"
expect 2 "a signal of no bits" "does not fit" "$work/empty-signal.dbc"
printf 'BO_ 256 M: 99 Node\n' >"$work/long.dbc"
expect 2 "a message longer than a CAN frame" "a CAN frame has at most 64" "$work/long.dbc"
printf 'BO_ 256 M: 8 Node\nBO_ 256 N: 8 Node\n' >"$work/twice.dbc"
expect 2 "an id defined twice" "defined twice" "$work/twice.dbc"

# Multiplexing: a message's multiplexor (M) decides which of its mN signals a frame has; what this decoder does
# not read is refused, never skipped.
printf 'BO_ 256 M: 8 Node\n SG_ S m5 : 0|8@1+ (1,0) [0|0] "" Node\n' >"$work/orphan.dbc"
expect 2 "a multiplexed signal without a multiplexor" "signal S is multiplexed, but the message has no multiplexor" \
  "$work/orphan.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ A M : 0|8@1+ (1,0) [0|0] "" Node\n SG_ B M : 8|8@1+ (1,0) [0|0] "" Node\n' >"$work/two.dbc"
expect 2 "two multiplexors in one message" "has a second multiplexor (B)" "$work/two.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ A M : 0|8@1+ (1,0) [0|0] "" Node\n SG_ B m1M : 8|8@1+ (1,0) [0|0] "" Node\n' >"$work/ext.dbc"
expect 2 "extended multiplexing" "extended multiplexing, which this decoder does not read" "$work/ext.dbc"
printf 'BO_ 256 M: 8 Node\n SG_ A : 0|8@1+ (1,0) [0|0] "" Node\nSG_MUL_VAL_ 256 A A 1-1;\n' >"$work/mulval.dbc"
expect 2 "an SG_MUL_VAL_ line" "a signal line this decoder does not read" "$work/mulval.dbc"
printf '(1.000000) vcan0 080#0103000000000000\n(1.001000) vcan0 080#0507E80320030A00\n' >"$work/command.log"
run "$dbc" "$work/command.log"
check "commands decode: exit 0 (got $code: $(cat "$work/err"))" test "$code" -eq 0
check "an arm command: its opcode and addressees, no set_deadband payload ($(head -1 "$work/out"))" \
  test "$(head -1 "$work/out")" = "1.000000 vcan0 LeverCommand Opcode=1 ToHsi=1 ToTop=1"
check "a set_deadband command: its payload ($(sed -n 2p "$work/out"))" \
  test "$(sed -n 2p "$work/out")" = \
  "1.001000 vcan0 LeverCommand Opcode=5 ToHsi=1 ToTop=1 Direction=1 Mode=0 P=0.1 Floor=0.8 FilterHz=1.0"

# The log: a file, a FIFO or stdin; lines that are no frames are errors (exit 1), each named, the first 20.
printf '(1.000000) vcan0 700#0100000000000000\n' >"$work/good.log"
run "$dbc" "$work/good.log"
check "a good frame decodes: exit 0 (got $code: $(cat "$work/err"))" test "$code" -eq 0
check "a good frame decodes: the HSI's heartbeat" grep -q "LeverHeartbeatHsi State=1" "$work/out"
# The settings frames bit for bit (docs/can-protocol.md's table), by payloads written out here by hand: every field
# a different value, then every field at its widest; a field one bit off, wide or narrow, changes a value.
# TOP: mode 1, changes 42, tares 21, taring, p 0x1234, floor 0xABCD, filter 0x8001.
# HSI: mode 0, changes 63, tares 63, not taring, p 0xFFFF, floor 0, filter 0xFFFF.
printf '(1.000000) vcan0 141#A9553412CDAB0180\n(1.000000) vcan0 140#FC3FFFFF0000FFFF\n' >"$work/settings.log"
timeout 10 "$decode" --json "$dbc" "$work/settings.log" >"$work/out" 2>"$work/err"; code=$?
check "settings frames decode: exit 0 (got $code: $(cat "$work/err"))" test "$code" -eq 0
settings_is() {  # settings_is LINE MESSAGE JQ_CONDITION
  check "settings frame $1: $2 where $3 (got $(sed -n "$1p" "$work/out"))" \
    jq -e --arg m "$2" "select(.message == \$m) | .signals | $3" <(sed -n "$1p" "$work/out") >/dev/null
}
settings_is 1 LeverSettingsTop '.Mode == 1 and .Changes == 42 and .Tares == 21 and .Taring == 1'
settings_is 1 LeverSettingsTop '(.P - 0.466 | fabs) < 1e-9 and (.Floor - 43.981 | fabs) < 1e-9 and (.FilterHz - 3276.9 | fabs) < 1e-9'
settings_is 2 LeverSettingsHsi '.Mode == 0 and .Changes == 63 and .Tares == 63 and .Taring == 0'
settings_is 2 LeverSettingsHsi '(.P - 6.5535 | fabs) < 1e-9 and .Floor == 0 and (.FilterHz - 6553.5 | fabs) < 1e-9'
check "settings frames: seven signals each, no more" \
  test "$(jq -c '.signals | keys' "$work/out" | sort -u)" = '["Changes","FilterHz","Floor","Mode","P","Tares","Taring"]'
expect 2 "a log that is a directory" "a directory, not a candump -L log" "$dbc" "$work/adir"
expect 2 "a log that is a device" "a device, not a candump -L log" "$dbc" /dev/zero
expect 2 "a missing log" "cannot read: No such file" "$dbc" "$work/none.log"
head -c 100000 /dev/urandom >"$work/random.log"
# A file that is no candump -L log at all: one line says so, not one line per line of it.
expect 2 "a log of random bytes" "random.log: not a candump -L log: none of its" "$dbc" "$work/random.log"
check "a log of random bytes: one line (got $(wc -l <"$work/err"))" test "$(wc -l <"$work/err")" -eq 1
expect 2 "a DBC given as the log" "lever.dbc: not a candump -L log" "$dbc" "$dbc"
check "a DBC given as the log: one line (got $(wc -l <"$work/err"))" test "$(wc -l <"$work/err")" -eq 1
# A log with some bad lines: each of the first 20 named, the rest counted, and how many were skipped.
{ cat "$work/good.log"; head -c 100000 /dev/urandom; echo; cat "$work/good.log"; } >"$work/partly.log"
expect 1 "a log with random bytes inside" "partly.log:2: not a candump -L frame" "$dbc" "$work/partly.log"
check "a log with random bytes inside: the rest counted" grep -q "more lines did not decode" "$work/err"
check "a log with random bytes inside: says how many were skipped" grep -qE "partly.log: [0-9]+ lines skipped, 2 frames decoded" "$work/err"
check "a log with random bytes inside: both frames decoded" test "$(grep -c LeverHeartbeatHsi "$work/out")" -eq 2
printf 'junk\n(1.000000) vcan0 700#010\n' >"$work/odd.log"
expect 2 "an odd number of hex digits, and nothing else" "odd.log: not a candump -L log" "$dbc" "$work/odd.log"
{ cat "$work/good.log"; printf '(1.000000) vcan0 700#010\n'; } >"$work/odd.log"
expect 1 "an odd number of hex digits" "$work/odd.log:2: not a candump -L frame" "$dbc" "$work/odd.log"
printf '(1.000000) vcan0 7FF#00\n(1.000000) vcan0 700#01\n' >"$work/unknown.log"
expect 1 "an id the DBC lacks, a wrong length" "7FF: an id the DBC does not define" "$dbc" "$work/unknown.log"
check "a wrong length too" grep -q "700: 1 bytes, not 8" "$work/err"
{ head -c 10000000 /dev/zero | tr '\0' A; echo; cat "$work/good.log"; } >"$work/longline.log"
expect 1 "a 10 MB line" "longer than 4096 bytes" "$dbc" "$work/longline.log"
check "a 10 MB line: the frame after it still decodes" grep -q "LeverHeartbeatHsi" "$work/out"
(sleep 0.2; cat "$work/good.log") >"$work/afifo" &
run "$dbc" "$work/afifo"
check "a log from a FIFO: decoded (exit $code)" test "$code" -eq 0
check "a log from a FIFO: its frame" grep -q "LeverHeartbeatHsi" "$work/out"
wait
timeout 10 "$decode" --summary "$dbc" - <"$work/good.log" >"$work/out" 2>"$work/err"; code=$?
check "stdin, --summary: exit 0 (got $code)" test "$code" -eq 0
check "stdin, --summary: one message counted" test "$(jq .messages.LeverHeartbeatHsi.frames "$work/out")" = 1
for i in $(seq 5000); do cat "$work/good.log"; done >"$work/many.log"
timeout 10 "$decode" "$dbc" "$work/many.log" 2>"$work/err" | head -n 1 >/dev/null
check "a reader that goes away (| head): no traceback" bash -c "! grep -q Traceback '$work/err'"

report "dbc-decode"
