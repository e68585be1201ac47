#!/bin/sh
# nerf-render honours --width/--height for every kind of view (the scene's
# own views and --path spiral scale their intrinsics with the image; one
# side alone keeps the aspect ratio), takes its frame size from the
# scene's images (after --downscale) when a path renders with --data,
# reads a scene that ships only images_K/ through --downscale K whatever
# the frame size, and refuses options that would change nothing instead
# of ignoring them.
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
# --downscale chooses the photos, --width/--height the frames: together.
render spiral-both --path spiral --frames 1 --downscale 2 --width 6 --height 4
[ "$(size "$work/spiral-both/r_000.png")" = 6x4 ] ||
  fail "spiral --downscale 2 --width 6 --height 4 gave" \
    "$(size "$work/spiral-both/r_000.png")"
# An orbit with --data: the scene's size, after --downscale; one side
# given keeps its aspect ratio.  Without --data: 100x100, and one side
# keeps the square.
render orbit-data --path orbit --frames 1
[ "$(size "$work/orbit-data/r_000.png")" = 24x16 ] ||
  fail "orbit with --data gave $(size "$work/orbit-data/r_000.png")"
render orbit-down --path orbit --frames 1 --downscale 2
[ "$(size "$work/orbit-down/r_000.png")" = 12x8 ] ||
  fail "orbit --downscale 2 gave $(size "$work/orbit-down/r_000.png")"
render orbit-w --path orbit --frames 1 --width 6
[ "$(size "$work/orbit-w/r_000.png")" = 6x4 ] ||
  fail "orbit --width 6 gave $(size "$work/orbit-w/r_000.png")"
$wrap "$render" --model "$work/model.nerf" --out "$work/orbit-sq" \
  --path orbit --frames 1 --width 6 2>"$work/orbit-sq.log" ||
  { cat "$work/orbit-sq.log"; fail "orbit --width 6 without --data"; }
[ "$(size "$work/orbit-sq/r_000.png")" = 6x6 ] ||
  fail "orbit --width 6 without --data gave $(size "$work/orbit-sq/r_000.png")"

# A scene that ships its photos at half size alone, as fern ships
# images_8/: the poses of a 48x32 capture beside the 24x16 one's photos
# in images_2/.  A path at any size reads it with --downscale 2.
$wrap "$scene" --out "$work/big" --capture forward --width 48 --height 32 \
  --train 4 --test 1 2>"$work/big.log" || { cat "$work/big.log"; exit 1; }
mkdir "$work/half"
cp "$work/big/poses_bounds.npy" "$work/half/"
cp -R "$work/scene/images" "$work/half/images_2"
$wrap "$render" --model "$work/model.nerf" --data "$work/half" \
  --downscale 2 --path spiral --frames 1 --width 12 --height 8 \
  --out "$work/half-spiral" 2>"$work/half.log" ||
  { cat "$work/half.log"; fail "images_2/ alone: spiral --downscale 2 at 12x8"; }
[ "$(size "$work/half-spiral/r_000.png")" = 12x8 ] ||
  fail "images_2/ alone: spiral gave $(size "$work/half-spiral/r_000.png")"
# Without --downscale a path takes the cameras from images_2/, the one
# folder there is, says so, and frames the photos' size.
$wrap "$render" --model "$work/model.nerf" --data "$work/half" \
  --path spiral --frames 1 --out "$work/half-auto" 2>"$work/auto.log" ||
  { cat "$work/auto.log"; fail "images_2/ alone: spiral without --downscale"; }
grep -q "reduced 2 times (as --downscale 2)" "$work/auto.log" ||
  { cat "$work/auto.log"; fail "images_2/ alone: which photos not said"; }
[ "$(size "$work/half-auto/r_000.png")" = 24x16 ] ||
  fail "images_2/ alone: spiral gave $(size "$work/half-auto/r_000.png")"

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
refused "--downscale chooses which photos of --data are read" \
  --path orbit --downscale 2
refused "--downscale chooses which photos of --data are read" \
  --poses "$work/scene/none.npy" --downscale 2
echo "ok"
