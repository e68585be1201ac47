#!/bin/sh
# nerf-render honours --width/--height for every kind of view (the scene's
# own views and --path spiral scale their intrinsics with the image; one
# side alone keeps the aspect ratio), and refuses options that would
# change nothing instead of ignoring them.
#
#   test-render-size.sh NERF-SCENE NERF-TRAIN NERF-RENDER
set -eu
scene=$1 train=$2 render=$3
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-render-size.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# A forward-facing scene of 24x16 images, so that a spiral is possible and
# the aspect ratio is not square.
$wrap "$scene" --out "$work/scene" --capture forward --width 24 --height 16 \
  --train 4 --test 1 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training and
# rendering pay for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

# size FILE: "WIDTHxHEIGHT" of a PNG, from its IHDR chunk.
size() {
  od -An -tu1 -j16 -N8 "$1" |
    awk '{ printf "%dx%d\n", $3 * 256 + $4, $7 * 256 + $8 }'
}

# render NAME ARGS...: render into $work/NAME, which must succeed.
render() {
  name=$1
  shift
  $wrap "$render" --model "$work/model.nerf" --data "$work/scene" \
    --out "$work/$name" "$@" 2>"$work/$name.log" ||
    { cat "$work/$name.log"; fail "$name: $*"; }
}

render spiral-wh --path spiral --frames 2 --width 12 --height 8
[ "$(size "$work/spiral-wh/r_001.png")" = 12x8 ] ||
  fail "spiral --width 12 --height 8 gave $(size "$work/spiral-wh/r_001.png")"
# Scaled intrinsics: the same view as the loader's own --downscale 2.
render spiral-down --path spiral --frames 2 --downscale 2
cmp -s "$work/spiral-wh/r_000.png" "$work/spiral-down/r_000.png" ||
  fail "spiral at 12x8 differs from spiral at --downscale 2"
render spiral-w --path spiral --frames 1 --width 6
[ "$(size "$work/spiral-w/r_000.png")" = 6x4 ] ||
  fail "spiral --width 6 gave $(size "$work/spiral-w/r_000.png")"
render spiral-h --path spiral --frames 1 --height 20
[ "$(size "$work/spiral-h/r_000.png")" = 30x20 ] ||
  fail "spiral --height 20 gave $(size "$work/spiral-h/r_000.png")"
render views --width 12 --height 8 --depth
[ "$(size "$work/views/r_000.png")" = 12x8 ] ||
  fail "--data views at 12x8 gave $(size "$work/views/r_000.png")"
[ "$(size "$work/views/depth_000.png")" = 12x8 ] || fail "depth size"

# refused WORDS ARGS...: exit 2, one line containing WORDS, no image.
refused() {
  words=$1
  shift
  status=0
  $wrap "$render" --model "$work/model.nerf" --out "$work/bad" "$@" \
    2>"$work/bad.log" || status=$?
  [ "$status" -eq 2 ] || { cat "$work/bad.log"; fail "$*: status $status"; }
  grep -qF -- "$words" "$work/bad.log" || { cat "$work/bad.log"; fail "$*"; }
  [ "$(wc -l <"$work/bad.log")" -eq 1 ] || { cat "$work/bad.log"; fail "$*"; }
  [ ! -e "$work/bad/r_000.png" ] || fail "$*: rendered anyway"
}
refused "--frames goes with --path" --data "$work/scene" --frames 3
refused "--frames goes with --path" --poses "$work/scene/none.npy" --frames 3
refused "--split chooses the views of --data" --data "$work/scene" \
  --path spiral --split train
refused "--split chooses the views of --data" --path orbit --split val
refused "--downscale shrinks the views" --path orbit --downscale 2
refused "--downscale shrinks the views" --data "$work/scene" \
  --poses "$work/scene/none.npy" --downscale 2
refused "give --downscale or --width/--height, not both" \
  --data "$work/scene" --downscale 2 --width 8
echo "ok"
