#!/usr/bin/env bash
# The package test: scripts/package for amd64 from BUILD_DIR and for arm64 and armhf from the cross trees the
# cross tests made (BUILD_DIR/cross/ARCH), into BUILD_DIR/dist, then check_packages.sh on them. An architecture
# whose build packages this machine cannot install (scripts/package exits 77) is left out, said so loudly; the
# cross test of that architecture shows as skipped.
# usage: run.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 source=$2
dist=$build/dist
rm -rf "$dist"
for arch in amd64 arm64 armhf; do
  tree=$build/cross/$arch
  [[ $arch == "$(dpkg --print-architecture)" ]] && tree=$build
  start=$SECONDS
  status=0
  "$source/scripts/package" "$arch" "$tree" "$dist" || status=$?
  if ((status == 77)); then
    echo "package: WARNING: no $arch packages: its build packages cannot be installed here" >&2
  elif ((status != 0)); then
    exit "$status"
  fi
  echo "package: $arch in $((SECONDS - start)) s"
done
exec "$source/tests/package/check_packages.sh" "$dist" "$source/packaging"
