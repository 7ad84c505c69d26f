#!/usr/bin/env bash
# An image test: this tree's packages (scripts/package), the board image with them installed and the test's files
# added (tools/board-image/build, its base cached), booted in virtual time (tools/board-image/boot), where
# lever-image-test.service runs tests/image/SCRIPT. Exits with the test's status; each step's wall time printed.
# usage: run.sh [--arch arm64] BUILD_DIR SOURCE_DIR SCRIPT [BOOT_OPTION...]
#   --arch arm64  the arm64 board: the packages of BUILD_DIR/cross/arm64 (the tree of the cross test, built)
set -euo pipefail
arch=amd64
[[ ${1:-} == --arch ]] && { arch=${2:?}; shift 2; }
build=$1 source=$2 script=$3
shift 3
tree=$build work=$build/image-test/${script%.sh}
[[ $arch == amd64 ]] || tree=$build/cross/$arch work=$build/image-test/$arch-${script%.sh}
rm -rf "$work"
mkdir -p "$work/dist" "$work/add"
t=$SECONDS
"$source/scripts/package" "$arch" "$tree" "$work/dist" >/dev/null
echo "image test: packages in $((SECONDS - t)) s"
# The board's test files: the unit that runs the test, the tests and the rig's gpio-sim helper at their places in
# the source tree (the scripts find each other by relative paths).
cp -a "$source/tools/board-image/guest/." "$work/add/"
lib=$work/add/usr/local/lib/lever-image-test
mkdir -p "$lib/tests" "$lib/tools/kernel-rig" "$lib/firmware"
cp -a "$source/tests/kernel" "$source/tests/image" "$lib/tests/"
cp -a "$source/tools/kernel-rig/gpio-sim-chip" "$lib/tools/kernel-rig/"
cp -a "$source/firmware/config" "$lib/firmware/"
t=$SECONDS
"$source/tools/board-image/build" --add "$work/add" "$arch" "$work/dist" "$work/image" >/dev/null
echo "image test: board image in $((SECONDS - t)) s ($(tr '\n' ';' <"$work/image/times"))"
t=$SECONDS
status=0
"$source/tools/board-image/boot" --out "$work/results" "$@" "$work/image" "$script" || status=$?
echo "image test: boot and test in $((SECONDS - t)) s"
rm -f "$work/image/disk.ext4"
exit "$status"
