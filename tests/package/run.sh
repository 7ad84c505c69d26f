#!/usr/bin/env bash
# The package test: scripts/package for amd64 from BUILD_DIR and for arm64 and armhf from the cross trees the
# cross tests made (BUILD_DIR/cross/ARCH), into BUILD_DIR/dist, then check_packages.sh on them. Every architecture
# must give its packages: one that cannot be built fails the test.
# usage: run.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 source=$2
dist=$build/dist
rm -rf "$dist"
for arch in amd64 arm64 armhf; do
  tree=$build/cross/$arch
  [[ $arch == "$(dpkg --print-architecture)" ]] && tree=$build
  start=$SECONDS
  "$source/scripts/package" "$arch" "$tree" "$dist" || { echo "package: no $arch packages (above)" >&2; exit 1; }
  echo "package: $arch in $((SECONDS - start)) s"
done
exec "$source/tests/package/check_packages.sh" "$dist" "$source/packaging"
