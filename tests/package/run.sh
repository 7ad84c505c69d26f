#!/usr/bin/env bash
# The package test: scripts/package for each architecture named (default amd64, arm64 and armhf), the build
# machine's from BUILD_DIR and the others from the cross trees the cross tests made (BUILD_DIR/cross/ARCH), into
# BUILD_DIR/dist, then check_packages.sh on them. Every architecture named must give its packages: one that cannot be
# built fails the test.
# usage: run.sh BUILD_DIR SOURCE_DIR [ARCH...]
set -euo pipefail
build=$1 source=$2
shift 2
archs=("$@")
((${#archs[@]})) || archs=(amd64 arm64 armhf)
dist=$build/dist
rm -rf "$dist"
for arch in "${archs[@]}"; do
  tree=$build/cross/$arch
  [[ $arch == "$(dpkg --print-architecture)" ]] && tree=$build
  start=$SECONDS
  "$source/scripts/package" "$arch" "$tree" "$dist" || { echo "package: no $arch packages (above)" >&2; exit 1; }
  echo "package: $arch in $((SECONDS - start)) s"
done
exec "$source/tests/package/check_packages.sh" "$dist" "$source/packaging" "${archs[@]}"
