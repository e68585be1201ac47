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
# MAIN JOB: generate the built-in scene, train the tiny preset on it,     #
# print the test PSNR and render an orbit.  Offline, a few minutes on 2   #
# cores.  Everything lands in out/demo/.                                  #
# ===================================================================== #
out=out/demo
mkdir -p "$out"
"$bin/nerf-info"
echo "== writing the built-in scene to $out/scene"
"$bin/nerf-scene" --out "$out/scene" --width 64 --height 64 --train 100 \
  --val 0 --test 8 --overwrite
echo "== training the tiny preset ($out/model.nerf)"
"$bin/nerf-train" --data "$out/scene" --out "$out/model.nerf" \
  --preset tiny --steps "${NERF_DEMO_STEPS:-1000}" --batch 256 --overwrite
echo "== evaluating on the 8 held-out test views"
"$bin/nerf-eval" --model "$out/model.nerf" --data "$out/scene"
echo "== rendering an orbit to $out/orbit"
"$bin/nerf-render" --model "$out/model.nerf" --out "$out/orbit" \
  --path orbit --frames 12 --width 64 --height 64 --depth --overwrite
# ===================================================================== #
# END OF MAIN JOB                                                       #
# ===================================================================== #

echo "== demo finished"
