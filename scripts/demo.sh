#!/usr/bin/env bash
#
# libnerf's demo: ./scripts/demo.sh
#
# Installs missing Debian packages (as root; otherwise prints the apt-get
# line), builds build/release and runs the main job (see "MAIN JOB" below).
# It needs no download and no arguments.

set -eu

cd "$(dirname "${BASH_SOURCE[0]}")/.."
# shellcheck source=scripts/deps.sh
. scripts/deps.sh

nerf_ensure_packages || exit 1

echo "== configure build/release"
nerf_configure build/release "${NERF_RELEASE_OPTIONS[@]}"
echo "== build"
meson compile -C build/release

bin=build/release/examples

# ===================================================================== #
# MAIN JOB                                                              #
#                                                                       #
# Replace this section when the model, renderer and trainer land.  The  #
# intended job: generate the built-in procedural scene, train the tiny  #
# preset on it, render an orbit of views, and print the test-split     #
# PSNR.  Keep it runnable offline and within a few minutes on 2 cores.  #
# ===================================================================== #
echo "== main job: library version and build information"
"$bin/nerf-info"
# ===================================================================== #
# END OF MAIN JOB                                                       #
# ===================================================================== #

echo "== demo finished"
