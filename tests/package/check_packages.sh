#!/usr/bin/env bash
# The Debian packages as an admin gets them (scripts/package): all three for every architecture named (default
# amd64, arm64 and armhf), their library dependencies found by dpkg-shlibdeps, a man page for every program, lintian
# on every package with no error and no warning; the build machine's packages installed, purged and checked in a
# throw-away root; the systemd units verified, a unit with a misspelt directive rejected by the same verify (so the
# check can fail), and each unit's systemd-analyze security exposure printed and held under a ceiling.
# usage: check_packages.sh DIST_DIR PACKAGING_SOURCE_DIR [ARCH...]
set -uo pipefail
dist=$1
units=$2/systemd
shift 2
archs=("$@")
((${#archs[@]})) || archs=(amd64 arm64 armhf)
source "$(dirname "$0")/../cli/lib.sh"
arch=$(dpkg --print-architecture)
shopt -s nullglob
debs=("$dist"/*.deb)
for deb_arch in "${archs[@]}"; do
  for pkg in lever-fw lever-bridge lever-tools; do
    found=("$dist/${pkg}_"*"_$deb_arch.deb")
    check "$pkg for $deb_arch is in $dist" test "${#found[@]}" -eq 1
  done
done

# Debian's library package of a soname (policy 8.1: libfoo.so.N in libfooN), where the name does not say it.
package_of_soname() {
  case $1 in
    libc.so.6 | libm.so.6 | ld-linux*) echo libc6 ;;
    libstdc++.so.6) echo libstdc++6 ;;
    libgcc_s.so.1) echo libgcc-s1 ;;
    *.so.*) local name=${1%%.so.*} version=${1##*.so.}; echo "$name$version" ;;
  esac
}
# Every library a program needs is named in its package's Depends (dpkg-shlibdeps found its package, which for a
# cross build lives in the sysroot: with no information found, CPack's --ignore-missing-info would leave it out).
for deb in "${debs[@]}"; do
  depends=$(dpkg-deb -f "$deb" Depends)
  mkdir -p "$work/x" && rm -rf "${work:?}/x/"* && dpkg-deb -x "$deb" "$work/x"
  for program in "$work"/x/usr/bin/*; do
    while read -r soname; do
      needed=$(package_of_soname "$soname")
      check "$(basename "$deb"): $(basename "$program") needs $soname, and Depends names $needed ($depends)" \
        grep -qxF "$needed" <(tr ',|' '\n\n' <<<"$depends" | awk '{ print $1 }')
    done < <(readelf -d "$program" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
    page=$work/x/usr/share/man/man1/$(basename "$program").1.gz
    check "$(basename "$deb"): $(basename "$program") has its man page" test -s "$page"
  done
done

# lintian: no error and no warning.
for deb in "${debs[@]}"; do
  lintian --tag-display-limit 0 --fail-on error,warning "$deb" >"$work/lintian" 2>&1
  code=$?
  check "lintian: $(basename "$deb") has no error or warning (exit $code)" test "$code" -eq 0
  echo "lintian $(basename "$deb"): $(grep -c '^E:' "$work/lintian") errors, $(grep -c '^W:' "$work/lintian") warnings"
  grep -v '^running with root privileges' "$work/lintian" | sed 's/^/  /'
done

# Install, remove, purge in a throw-away root. The root holds no libc or systemd, so dependencies are forced;
# the maintainer scripts run without chroot (there is nothing in the root to run them with) and must honour
# DPKG_ROOT: the system users go into the root's /etc/passwd, and the running system is not touched.
root=$work/root
admin=$root/var/lib/dpkg
mkdir -p "$admin/info" "$admin/updates" "$root/etc" && : >"$admin/status" && : >"$admin/available"
host_passwd=$(sha256sum /etc/passwd /etc/group)
dpkg_root() { dpkg --root="$root" --force-script-chrootless --force-depends --log=/dev/null "$@"; }
for pkg in lever-fw lever-bridge lever-tools; do
  dpkg_root -i "$dist/${pkg}_"*"_$arch.deb" >"$work/dpkg" 2>&1
  check "install $pkg into a throw-away root: $(tail -n3 "$work/dpkg" | tr '\n' ' ')" test $? -eq 0
done
for file in /usr/bin/lever-fw /usr/bin/lever-bridge /usr/bin/lever-codec /usr/bin/lever-hil /usr/bin/lever-ctl /usr/bin/lever-view /usr/bin/lever-plot /usr/bin/lever-study \
  /etc/lever/top.toml /etc/lever/hsi.toml /etc/lever/top-float32.toml /etc/lever/bridge-example.toml \
  /lib/systemd/system/lever-fw@.service /lib/systemd/system/lever-bridge@.service \
  /lib/udev/rules.d/60-lever-gpio-pwm.rules /usr/share/doc/lever-fw/copyright \
  /usr/share/doc/lever-tools/changelog.Debian.gz; do
  check "installed: $file" test -e "$root$file"
done
check "no key shipped" test ! -e "$root/etc/lever/keys"
check "the examples are conffiles" \
  grep -q "/etc/lever/top.toml" <(dpkg-query --admindir="$admin" -W -f='${Conffiles}' lever-fw)
check "postinst made the user lever, in groups gpio and dialout" \
  grep -qE '^gpio:[^:]*:[0-9]+:(.*,)?lever(,|$)' "$root/etc/group"
check "postinst made the user lever-bridge" grep -q '^lever-bridge:' "$root/etc/passwd"
check "the running system's users are untouched" test "$(sha256sum /etc/passwd /etc/group)" = "$host_passwd"
"$root/usr/bin/lever-fw" --config "$root/etc/lever/top.toml" --check-config >/dev/null
check "the installed lever-fw reads the installed configuration" test $? -eq 0
dpkg_root -r lever-fw lever-bridge lever-tools >"$work/dpkg" 2>&1
check "remove: $(tail -n2 "$work/dpkg" | tr '\n' ' ')" test $? -eq 0
check "remove: the programs are gone" test ! -e "$root/usr/bin/lever-fw"
check "remove: the edited-or-not conffiles stay" test -e "$root/etc/lever/top.toml"
dpkg_root -P lever-fw lever-bridge lever-tools >"$work/dpkg" 2>&1
check "purge: $(tail -n2 "$work/dpkg" | tr '\n' ' ')" test $? -eq 0
left=$(cd "$root" && find . -not -type d -not -path './var/lib/dpkg/*' -not -path './etc/passwd*' \
  -not -path './etc/group*' -not -path './etc/shadow*' -not -path './etc/gshadow*' -not -path './etc/.pwd.lock' | sort)
check "purge leaves nothing but dpkg's database and the users (left: ${left:-nothing})" test -z "$left"

# The units: systemd-analyze verify where the programs they start exist (it checks ExecStart= paths).
for unit in lever-fw@top lever-bridge@site-a; do
  template=${unit%@*}@.service
  systemd-analyze verify --man=no "$units/$template" >"$work/verify" 2>&1
  grep -v -e 'is not executable' -e 'Command .* not found' "$work/verify" >"$work/verify.real"
  check "verify $template: $(cat "$work/verify.real")" test ! -s "$work/verify.real"
done
mkdir -p "$work/typo"
sed 's/^NoNewPrivileges=/NoNewPrivilege=/' "$units/lever-fw@.service" >"$work/typo/lever-fw@.service"
systemd-analyze verify --man=no "$work/typo/lever-fw@.service" >"$work/verify" 2>&1
check "verify rejects a misspelt directive" grep -q "Unknown key 'NoNewPrivilege'" "$work/verify"

# Exposure (0 safest, 10 none), offline on the unit files; each held at its level now, so that a hardening line lost fails.
for unit in lever-fw@.service:2.0 lever-bridge@.service:1.7; do
  name=${unit%:*} ceiling=${unit#*:}
  systemd-analyze security --offline=yes --threshold="${ceiling/./}" "$units/$name" >"$work/security" 2>&1
  code=$?
  echo "systemd-analyze security: $(grep -o 'Overall exposure level.*' "$work/security")"
  check "$name: exposure at most $ceiling (exit $code)" test "$code" -eq 0
done
report "packages"
