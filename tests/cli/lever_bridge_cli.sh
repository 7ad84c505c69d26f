#!/usr/bin/env bash
# lever-bridge as a user runs it, on bad input above all: exit code (0, 1 runtime, 2 bad input), the message, and
# what is left on disk, for keys (keygen --out, key files), --check-config, the TOML file, the command line, the
# addresses, and a machine without a CAN stack or interface. Nothing here opens a CAN interface successfully: the
# relay itself is tested in the kernel rig (tests/kernel/bridge_*.sh).
# usage: lever_bridge_cli.sh path/to/lever-bridge
set -uo pipefail
bridge=$(realpath "$1")
source "$(dirname "$0")/lib.sh"
bad_cases=0
mkdir -p "$work/io"  # stdout and stderr of each run, outside what the disk checks look at
snapshot() { (cd "$work" && find . \( -path ./run -o -path ./io \) -prune -o -printf '%p %s %m %T@\n' | sort); }
run() {  # run ARGS...: in $work/run, never more than 10 s; sets code
  mkdir -p "$work/run"
  (cd "$work/run" && timeout 10 "$bridge" "$@" >"$work/io/out" 2>"$work/io/err")
  code=$?
}
expect() {  # expect CODE NAME EXPECTED_MESSAGE ARGS...: exit code, message, and nothing new or changed on disk
  local want=$1 name=$2 expected=$3; shift 3
  [[ $want -eq 2 ]] && bad_cases=$((bad_cases + 1))
  local before; before=$(snapshot)
  run "$@"
  check "$name: exit code $want (got $code)" test "$code" -eq "$want"
  check "$name: says '$expected'" grep -qF -- "$expected" "$work/io/err"
  check "$name: one line" test "$(wc -l <"$work/io/err")" -le 2
  check "$name: leaves the disk as it was" test "$before" == "$(snapshot)"
  check "$name: nothing in the working directory" test -z "$(ls -A "$work/run")"
}
expect_bad() { expect 2 "$@"; }
ok() { check "$1: exit code 0 (got $code; $(head -c 300 "$work/io/err"))" test "$code" -eq 0; }

key=$work/site.key
net=(--can vcan0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001)

# ---- Help and exit codes ----
run --help; ok "--help"
check "--help documents the exit codes" grep -q "2 bad input" "$work/io/out"
check "--help documents --check-config and --peer-site-id" grep -q -- "--peer-site-id" "$work/io/out"
run keygen --help; ok "keygen --help"
check "keygen --help documents --out" grep -q -- "--out" "$work/io/out"
expect_bad "an unknown option" "--frobnicate" --frobnicate
expect_bad "a misspelt subcommand" "keygn" keygn

# ---- Keys ----
run keygen --out "$key"; ok "keygen --out"
check "keygen --out: mode 0600" test "$(stat -c %a "$key")" = 600
check "keygen --out: 64 hex digits and a newline" grep -qxE '[0-9a-f]{64}' "$key"
check "keygen --out: 65 bytes" test "$(stat -c %s "$key")" -eq 65
check "keygen --out: the key loads" bash -c "'$bridge' ${net[*]} --key '$key' --check-config >/dev/null"
sum=$(sha256sum <"$key")
expect_bad "keygen --out an existing key" "never overwritten" keygen --out "$key"
check "the existing key is untouched" test "$sum" == "$(sha256sum <"$key")"
expect_bad "keygen --out in a missing directory" "No such file or directory" keygen --out "$work/none/site.key"
mkdir -p "$work/dir"
expect_bad "keygen --out a directory" "exists" keygen --out "$work/dir"
ln -s "$work/target.key" "$work/link.key"
expect_bad "keygen --out a dangling symlink" "exists" keygen --out "$work/link.key"
check "nothing created at the symlink's target" test ! -e "$work/target.key"
# A special file of our own rather than /dev/null: a regression here, run as root, must not cost the machine its
# /dev/null (a key writer without O_EXCL fails to fsync a device and then removes "its" file).
mkfifo "$work/fifo"
expect_bad "keygen --out a FIFO" "never overwritten" keygen --out "$work/fifo"
check "the FIFO is still a FIFO" test -p "$work/fifo"
(umask 000 && "$bridge" keygen --out "$work/umask.key" 2>/dev/null)
check "keygen --out under umask 000: still mode 0600" test "$(stat -c %a "$work/umask.key")" = 600
run keygen; ok "keygen to stdout"
check "keygen to stdout: one key" grep -qxE '[0-9a-f]{64}' "$work/io/out"
run keygen --out -; ok "keygen --out -"
check "keygen --out -: stdout" grep -qxE '[0-9a-f]{64}' "$work/io/out"

cp "$key" "$work/open.key" && chmod 644 "$work/open.key"
expect_bad "a key readable by others" "chmod 600" "${net[@]}" --key "$work/open.key" --check-config
expect_bad "a missing key file" "cannot open: No such file" "${net[@]}" --key "$work/none.key" --check-config
(umask 077 && printf '%064d\n' 0 >"$work/zero.key")
expect_bad "an all-zero key" "all zeros" "${net[@]}" --key "$work/zero.key" --check-config
(umask 077 && printf '%s\r\n' "$(head -c 64 "$key")" >"$work/crlf.key")
expect_bad "a key with a CRLF ending" "carriage return" "${net[@]}" --key "$work/crlf.key" --check-config
expect_bad "a directory as key" "not a regular file" "${net[@]}" --key "$work/dir" --check-config
expect_bad "no key" "--key is required" "${net[@]}" --check-config
expect_bad "--insecure with --key" "exclude each other" "${net[@]}" --key "$key" --insecure --check-config

# ---- --check-config: validates, opens nothing ----
# 192.0.2.1 (TEST-NET-1) is no address of this machine: binding it would fail, so success shows nothing was opened.
run --can vcan0 --bind 192.0.2.1:5000 --peer 192.0.2.7:5000 --key "$key" --check-config; ok "--check-config"
check "--check-config: says valid" grep -q "configuration valid" "$work/io/out"
mkdir -p "$work/etc"
cp "$key" "$work/etc/site.key"
printf 'can = "vcan0"\nbind = "127.0.0.1:5000"\npeer = "127.0.0.1:5001"\nkey = "site.key"\n' >"$work/etc/bridge.toml"
run --config "$work/etc/bridge.toml" --check-config; ok "a config file with a key relative to it, from elsewhere"
check "the key was found next to the config" grep -qF "$work/etc/site.key" "$work/io/out"
printf 'can = "vcan0"\nbind = "127.0.0.1:5000"\npeer = "127.0.0.1:5001"\nkey = "other.key"\n' >"$work/etc/other.toml"
expect_bad "a relative key missing next to the config" "$work/etc/other.key" --config "$work/etc/other.toml" --check-config
printf 'can = "vcan0"\nbind = "127.0.0.1:5000"\npeer = "127.0.0.1:5001"\nkey = "site.key"\nrealtime_priority = 0\npeer_site_id = 2\nsite_id = 1\n' \
  >"$work/etc/rt.toml"
run --config "$work/etc/rt.toml" --check-config; ok "realtime_priority, site_id and peer_site_id as TOML keys"
expect_bad "a missing config file" "bridge-none.toml" --config "$work/bridge-none.toml" --check-config
expect_bad "a directory as config" "$work/dir: a directory, not a configuration file" --config "$work/dir" --check-config
expect_bad "/dev/zero as config (no hang)" "/dev/zero: a device" --config /dev/zero --check-config
expect_bad "a FIFO as config (no hang)" "a FIFO, not a configuration file" --config "$work/fifo" --check-config
head -c 2000000 /dev/zero | tr '\0' '#' >"$work/etc/huge.toml"
expect_bad "a 2 MB config" "a configuration file is at most 1048576" --config "$work/etc/huge.toml" --check-config
printf '\xef\xbb\xbfcan = "vcan0"\n' >"$work/etc/bom.toml"
run --config "$work/etc/bom.toml" --check-config
check "a config with a UTF-8 BOM is read (exit 2 for the missing bind, got $code)" grep -q "bind (key 'bind') is required" "$work/io/err"

# ---- --get: one key's effective value, what scripts read a configuration with ----
run --config "$work/etc/rt.toml" --get key; ok "--get key"
check "--get key: the path from the config's directory, without quotes" test "$(cat "$work/io/out")" == "$work/etc/site.key"
run --config "$work/etc/bridge.toml" --get site_id; ok "--get an unset key"
check "--get an unset key: an empty line" test "$(cat "$work/io/out")" == ""
run --config "$work/etc/rt.toml" --get site_id --site-id 7; ok "--get a key the command line sets"
check "--get: the command line wins over the file" test "$(cat "$work/io/out")" == "7"
expect_bad "--get an unknown key" "--get: no key 'nope'; the keys: can, bind, peer" --config "$work/etc/bridge.toml" --get nope
expect_bad "--get with --check-config" "excludes" --config "$work/etc/bridge.toml" --get peer --check-config
expect_bad "--get on a configuration that is not valid" "--key is required" "${net[@]}" --get peer

# ---- The TOML file: each value refused at load, naming the file, the key and the value or its type ----
toml_bad() {  # toml_bad NAME MESSAGE LINE
  printf 'can = "vcan0"\nbind = "127.0.0.1:5000"\npeer = "127.0.0.1:5001"\nkey = "site.key"\n%s\n' "$3" \
    >"$work/etc/bad.toml"
  expect_bad "TOML: $1" "$2" --config "$work/etc/bad.toml" --check-config
}
toml_bad "stats_interval_s NaN" "stats_interval_s: must be a number of s in [0.01, 3600], got nan" "stats_interval_s = nan"
toml_bad "probe_interval_s infinite" "probe_interval_s: must be a number of s in [0.01, 3600], got inf" "probe_interval_s = inf"
toml_bad "probe_interval_s 0" "got 0" "probe_interval_s = 0"
toml_bad "record_keep_files fractional" "record_keep_files: must be a whole number in [1, 1000], got 2.5" "record_keep_files = 2.5"
toml_bad "record_keep_files NaN" "record_keep_files: must be a whole number in [1, 1000], got nan" "record_keep_files = nan"
toml_bad "can_bitrate fractional" "can_bitrate: must be a whole number in [10000, 1000000], got 500000.5" "can_bitrate = 500000.5"
toml_bad "can_bitrate NaN" "can_bitrate: must be a whole number in [10000, 1000000], got nan" "can_bitrate = nan"
toml_bad "site_id fractional" "site_id: must be a whole number in [0, 255], got 2.5" "site_id = 2.5"
toml_bad "site_id 300" "got 300" "site_id = 300"
toml_bad "peer_site_id negative" "peer_site_id: must be a whole number in [0, 255], got -1" "peer_site_id = -1"
toml_bad "site_id equal to peer_site_id" "site_id and peer_site_id are both 4" $'site_id = 4\npeer_site_id = 4'
toml_bad "realtime_priority 100" "realtime_priority: must be a whole number in [0, 99], got 100" "realtime_priority = 100"
toml_bad "record_rotate_mb huge" "record_rotate_mb: must be a number of MB in [0, 1e+06], got 1e+300" "record_rotate_mb = 1e300"
toml_bad "record_rotate_mb NaN" "got nan" "record_rotate_mb = nan"
toml_bad "stats_json a string" "stats_json: must be true or false, got a string" 'stats_json = "yes"'
toml_bad "an unknown key" "bad.toml: realtime: unknown key" "realtime = 1"
toml_bad "an empty allow-list" "allow: must not be empty" 'allow = ""'
toml_bad "an id beyond 11 bits" "beyond 11 bits" 'allow_to_network = "0x800"'
toml_bad "an empty record path" "record: must not be empty" 'record = ""'
toml_bad "a syntax error" "bad.toml:5" "stats_json = "
printf 'can = ""\nbind = "127.0.0.1:5000"\npeer = "127.0.0.1:5001"\nkey = "site.key"\n' >"$work/etc/bad.toml"
expect_bad "TOML: an empty interface" "bad.toml: can: must not be empty" --config "$work/etc/bad.toml" --check-config
printf 'can = 5\n' >"$work/etc/bad.toml"
expect_bad "TOML: a number for a string" "bad.toml: can: must be a string, got an integer" --config "$work/etc/bad.toml" --check-config
printf 'peer = "127.0.0.1:0"\ncan = "vcan0"\nbind = "127.0.0.1:5000"\nkey = "site.key"\n' >"$work/etc/bad.toml"
expect_bad "TOML: peer port 0" "peer '127.0.0.1:0': port 0" --config "$work/etc/bad.toml" --check-config

# ---- The command line ----
expect_bad "--allow empty" "--allow: allow-list is empty" "${net[@]}" --key "$key" --allow ""
expect_bad "--allow beyond 11 bits" "--allow: allow-list item '0x900'" "${net[@]}" --key "$key" --allow 0x900
expect_bad "--record empty" "--record: the path is empty" "${net[@]}" --key "$key" --record ""
expect_bad "--key empty" "--key: the path is empty" "${net[@]}" --key ""
expect_bad "--site-id fractional" "--site-id" "${net[@]}" --key "$key" --site-id 2.5
expect_bad "--site-id 256" "--site-id" "${net[@]}" --key "$key" --site-id 256
expect_bad "--peer-site-id the own site id" "both 3" "${net[@]}" --key "$key" --site-id 3 --peer-site-id 3
expect_bad "--realtime-priority 100" "--realtime-priority" "${net[@]}" --key "$key" --realtime-priority 100
expect_bad "--realtime-priority -1" "--realtime-priority" "${net[@]}" --key "$key" --realtime-priority -1
expect_bad "--realtime-priority nan" "--realtime-priority" "${net[@]}" --key "$key" --realtime-priority nan
expect_bad "--can missing" "--can (key 'can') is required" --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key"
expect_bad "--can too long" "not an interface name" --can a-name-far-too-long --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key"
expect_bad "--can with a slash" "not an interface name" --can ../can0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key"

# ---- The recording: a regular file of its own, never a device, a directory, a symlink, the key or the config ----
expect_bad "--record a directory" "record '$work/dir': a directory" "${net[@]}" --key "$key" --record "$work/dir"
expect_bad "--record a FIFO" "a FIFO" "${net[@]}" --key "$key" --record "$work/fifo"
expect_bad "--record /dev/null" "record '/dev/null': a device" "${net[@]}" --key "$key" --record /dev/null
ln -s "$work/elsewhere.log" "$work/record-link.log"
expect_bad "--record a symlink" "a symbolic link" "${net[@]}" --key "$key" --record "$work/record-link.log"
expect_bad "--record in a missing directory" "the directory '$work/none' does not exist" "${net[@]}" --key "$key" \
  --record "$work/none/a.log"
expect_bad "--record the key file" "is the key file" "${net[@]}" --key "$key" --record "$key"
expect_bad "record the configuration file" "is the configuration file" --config "$work/etc/bridge.toml" \
  --record "$work/etc/bridge.toml"
check "the key is still the key" test "$sum" == "$(sha256sum <"$key")"

# ---- Long and unprintable values: echoed cut short and with control bytes as '?' ----
big=$(head -c 100000 /dev/zero | tr '\0' x)
expect_bad "a 100 kB --allow" "allow-list item 'xxx" "${net[@]}" --key "$key" --allow "0x1,$big"
check "a 100 kB --allow: a short message (got $(wc -c <"$work/io/err") bytes)" test "$(wc -c <"$work/io/err")" -lt 300
expect_bad "a 100 kB --key" "cannot open" "${net[@]}" --key "$big"
check "a 100 kB --key: a short message (got $(wc -c <"$work/io/err") bytes)" test "$(wc -c <"$work/io/err")" -lt 400
expect_bad "a 100 kB --peer" "peer '" --can vcan0 --bind 127.0.0.1:5000 --peer "$big:1" --key "$key"
check "a 100 kB --peer: a short message (got $(wc -c <"$work/io/err") bytes)" test "$(wc -c <"$work/io/err")" -lt 400
# ESC is a name the kernel allows (dev_valid_name refuses only '/', ':' and white space): no such interface here,
# a runtime failure, with the name shown and its control byte defused.
expect 1 "an escape sequence in --can" "a?[31mb" --can $'a\e[31mb' --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key"
expect_bad "a colon in --can" "can 'can:0': not an interface name: contains ':'" --can can:0 --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key"
expect_bad "a '%' in --can" "can 'can%d': not an interface name: contains '%'" --can 'can%d' --bind 127.0.0.1:5000 --peer 127.0.0.1:5001 --key "$key"
check "no control byte reaches the terminal" bash -c "! grep -qP '\\x1b' '$work/io/err'"

# ---- Addresses ----
addr_bad() {  # addr_bad NAME MESSAGE BIND PEER
  expect_bad "$1" "$2" --can vcan0 --bind "$3" --peer "$4" --key "$key"
}
addr_bad "peer port 0" "peer '127.0.0.1:0': port 0" 127.0.0.1:5000 127.0.0.1:0
addr_bad "bind port 0" "bind '127.0.0.1:0': port 0" 127.0.0.1:0 127.0.0.1:5001
addr_bad "a broadcast peer" "peer '255.255.255.255:5001': a broadcast address" 0.0.0.0:5000 255.255.255.255:5001
addr_bad "a multicast peer" "peer '239.1.2.3:5001': a multicast address" 0.0.0.0:5000 239.1.2.3:5001
addr_bad "an IPv6 multicast peer" "a multicast address" '[::]:5000' '[ff02::1]:5001'
addr_bad "the unspecified peer" "the unspecified address" 127.0.0.1:5000 0.0.0.0:5001
addr_bad "a peer equal to the bind address" "this bridge's own address" 127.0.0.1:5000 127.0.0.1:5000
addr_bad "a loopback peer on our wildcard port" "this bridge's own address" 0.0.0.0:5000 127.0.0.1:5000
addr_bad "a multicast bind" "bind '224.0.0.1:5000': a multicast address" 224.0.0.1:5000 127.0.0.1:5001
addr_bad "mixed families" "different address families" 127.0.0.1:5000 '[::1]:5001'
addr_bad "a port beyond 64 bits" "port from 0 to 65535" 127.0.0.1:5000 127.0.0.1:99999999999999999999999
addr_bad "no port" "expected HOST:PORT" 127.0.0.1:5000 127.0.0.1
addr_bad "an IPv6 address without brackets" "expected HOST:PORT" 127.0.0.1:5000 ::1:5001

# ---- Runtime failures: exit 1, a message saying what to do, nothing on disk ----
# This machine may or may not have a kernel CAN stack; either way lvrnone0 does not exist.
run --can lvrnone0 --bind 127.0.0.1:5123 --peer 127.0.0.1:5001 --key "$key" --record rec.log
check "no CAN: exit 1 (got $code)" test "$code" -eq 1
check "no CAN: says what to do (modprobe can-raw, or ip link)" grep -qE "modprobe can-raw|ip link show lvrnone0" "$work/io/err"
check "no CAN: no recording left behind" test ! -e "$work/run/rec.log"
run --can vcan0 --bind 192.0.2.1:5000 --peer 192.0.2.7:5000 --key "$key"
check "binding an address this machine does not have: exit 1 (got $code)" test "$code" -eq 1
check "and names it" grep -q "192.0.2.1:5000" "$work/io/err"

# ---- The documented examples (docs/bridge.md, packaging/config/bridge-example.toml), checked rather than run ----
mkdir -p "$work/doc"
(cd "$work/doc" && "$bridge" keygen --out site.key 2>/dev/null)
check "docs: keygen --out site.key" test "$(stat -c %a "$work/doc/site.key")" = 600
(cd "$work/doc" && "$bridge" --can can0 --bind 0.0.0.0:5000 --peer 192.0.2.7:5000 --key site.key --site-id 1 \
  --peer-site-id 2 --record site-a.log --stats-json --check-config >/dev/null)
check "docs: the bridge.md command line is valid" test $? -eq 0
check "docs: and --check-config left no recording" test ! -e "$work/doc/site-a.log"
example=$(dirname "$0")/../../packaging/config/bridge-example.toml
sed "s|/etc/lever/keys/site.key|site.key|" "$example" >"$work/doc/bridge.toml"
"$bridge" --config "$work/doc/bridge.toml" --check-config >/dev/null
check "docs: bridge-example.toml is valid (its key next to it)" test $? -eq 0

echo "lever-bridge cli: $bad_cases bad-input cases (exit 2)"
report "lever-bridge cli"
