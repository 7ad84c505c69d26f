#!/usr/bin/env bash
# Runs inside the kernel rig: a lever-bridge on vcan1 is attacked over UDP. Forged, tampered, replayed,
# truncated, oversized, reflected and third-address datagrams must be dropped and counted; nothing of theirs may
# reach the bus. Each attack uses its own CAN id (0x101 + kind), so candump shows what got through.
# usage: bridge_attacks.sh BIN_DIR
set -uo pipefail
. "$(dirname "$0")/lib.sh"

"$bin/lever-bridge" --can vcan1 --bind 127.0.0.1:5001 --peer 127.0.0.1:5000 --key "$key" --site-id 2 \
  --stats-json >"$out/victim.stats" 2>"$out/victim.err" &
bridge=$!
candump -r 8388608 -L vcan1 >"$out/vcan1.log" &
dump=$!
check "the bridge and the candump are up" wait_until_true 60 all_waiting $bridge $dump

attack() {  # attack KIND FROM SEQUENCE [extra]
  "$bin/lever-bridge-attack" --key "$key" --from "$2" --to 127.0.0.1:5001 --kind "$1" --count 20 \
    --sequence "$3" "${@:4}" >>"$out/attacks.txt"
}
attack valid 127.0.0.1:5000 1000
attack forged 127.0.0.1:5000 2000
attack tampered 127.0.0.1:5000 3000
attack replayed 127.0.0.1:5000 4000
attack truncated 127.0.0.1:5000 5000
attack oversized 127.0.0.1:5000 6000
attack reflected 127.0.0.1:5000 7000 --sender 2
attack valid 127.0.0.2:5000 8000               # a third address, with the right key
attack garbage 127.0.0.1:5000 0                  # random bytes of random lengths
attack valid 127.0.0.1:5000 9000                # still relaying after all that
sleep 0.5
kill -TERM $bridge; wait $bridge; code=$?
kill $dump; wait $dump 2>/dev/null

count() { grep -c " $1#" "$out/vcan1.log"; }
stat() { tail -1 "$out/victim.stats" | jq ".from_network.$1"; }
check "the bridge exits 0" test "$code" -eq 0
check "valid datagrams from the peer got through (2 x 20)" test "$(count 101)" -eq 40
check "forged: none through" test "$(count 102)" -eq 0
check "tampered: none through" test "$(count 103)" -eq 0
check "replayed: only the genuine first one through" test "$(count 104)" -eq 1
check "truncated: none through" test "$(count 105)" -eq 0
check "oversized: none through" test "$(count 106)" -eq 0
check "reflected: none through" test "$(count 107)" -eq 0
check "forged and tampered counted as authentication failures" test "$(stat auth_failures)" -eq 40
check "replays counted as duplicates" test "$(stat duplicates)" -eq 19
check "truncated, oversized and garbage counted as malformed (3 x 20)" test "$(stat malformed)" -eq 60
check "reflections counted" test "$(stat reflected)" -eq 20
check "the third address counted" test "$(stat foreign_source)" -ge 20
check "nothing else reached the bus" test "$(grep -cv ' 10[1-7]#' "$out/vcan1.log")" -eq 0

finish "bridge attacks"
