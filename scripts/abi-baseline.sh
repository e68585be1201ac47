#!/bin/sh
# Rewrite the ABI baseline, tests/abi/libnerf.abi and libnerf-types.abi,
# from a build:  scripts/abi-baseline.sh [BUILD_DIR]  (default build/release)
#
# Deliberate only: when a release is tagged, when the soname moves, or for
# a break while libnerf is 0.x (docs/abi-versioning.md).  Commit the
# baselines with the change that made them differ and say why.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build/release}
if [ ! -f "$build/build.ninja" ]; then
  echo "$build is not a configured build directory (meson setup $build ...)" >&2
  exit 1
fi
exec meson compile -C "$build" abi-baseline
