# Sourced by the kernel-rig test scripts: results directory, scratch space, checks, and a shared key.
# Sets: bin (the first argument: where lever-bridge lives), out, work, key; defines check and finish.
bin=$1
out=${LEVER_RIG_OUT:-$(mktemp -d)}
work=$(mktemp -d)
passed=0 failed=0

check() {  # check NAME COMMAND...: run the command, count and print the result
  local name=$1; shift
  if "$@"; then passed=$((passed + 1)); echo "ok: $name"; else failed=$((failed + 1)); echo "FAILED: $name" >&2; fi
}

# jq_true FILE FILTER: the filter gives exactly `true` on FILE (a JSON document; "-" for stdin). Within the filter
# `num` passes a figure on and fails on anything else, so that a missing figure (null: jq sorts it below every
# number, and JSON carries a NaN as null) fails the comparison instead of passing it: write
# `(.latency.x.max | num) <= 2.1`. A jq error (num's included) is a false.
jq_prelude='def num: if type == "number" and (isnan | not) and (isinfinite | not) then . else error("not a figure: \(tojson)") end;'
jq_true() { [[ $(jq -r "$jq_prelude $2" "$1" 2>/dev/null) == true ]]; }

finish() {  # finish TITLE: the closing line, and the exit status
  echo "$1: $passed passed, $failed failed"
  [[ $failed -eq 0 ]]
}

# wait_until_true SECONDS COMMAND...: until the command succeeds, polling every 10 ms (the guest's time where it
# runs in virtual time). The seconds bound only a failure: a pass waits as long as the condition takes.
wait_until_true() {
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do
    ((SECONDS < deadline)) || { echo "timed out waiting for: $*" >&2; return 1; }
    sleep 0.01
  done
}
# waiting PID: the process's main thread sleeps in select, poll or epoll, so its set-up is done. candump gets there
# once its socket is bound with its filters (it misses no frame sent after); lever-bridge once its sockets are
# bound, its relay threads run and their real-time policy is set or refused (Relay::run's loop).
waiting() { [[ $(cat "/proc/$1/wchan" 2>/dev/null) =~ ^(do_select|core_sys_select|do_sys_poll|ep_poll)$ ]]; }
all_waiting() { local pid; for pid in "$@"; do waiting "$pid" || return 1; done; }  # all_waiting PID...
# logged FILE ID N: a candump -L log holds at least N frames of ID (candump writes each frame as it comes)
logged() { (($(grep -c " $2#" "$1" 2>/dev/null) >= $3)); }

# The observers (candump) get 8 MB receive buffers: under TCG a busy guest otherwise lets them drop a few frames
# that the bridges did relay (seen: 997 of 1000 logged on the sending side, 1000 relayed and received).

key=$work/site.key
"$bin/lever-bridge" keygen --out "$key" 2>/dev/null
