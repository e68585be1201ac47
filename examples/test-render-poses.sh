#!/bin/sh
# shellcheck disable=SC2086 # $wrap is empty or a command to split
# nerf-render --poses on a tiny model trained here for two steps: the
# scene's own transforms_test.json (with and without a size of its own), a
# .npy camera path written byte by byte, and files it must refuse.
#
#   test-render-poses.sh NERF-SCENE NERF-TRAIN NERF-RENDER
set -eu
scene=$1 train=$2 render=$3
# In a cross build meson names the cross file's exe_wrapper (qemu-user,
# say) that runs the programs; natively it is unset and they run as is.
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-render-poses.XXXXXX")
trap 'rm -rf "$work"' EXIT

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 2 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training and
# rendering pay for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

fail() {
  echo "FAIL: $*"
  exit 1
}

# expect_png FILE W H: FILE is a PNG of W x H pixels (read from IHDR).
expect_png() {
  [ -f "$1" ] || fail "$1 was not written"
  size=$(od -An -tu1 -j16 -N8 "$1" |
    awk '{ print $3 * 256 + $4 "x" $7 * 256 + $8 }')
  [ "$size" = "$2x$3" ] || fail "$1 is $size, expected $2x$3"
}

# run NAME ARGS...: nerf-render into $work/NAME; its stderr in NAME.log.
run() {
  name=$1
  shift
  $wrap "$render" --model "$work/model.nerf" --out "$work/$name" "$@" \
    2>"$work/$name.log" || { cat "$work/$name.log"; fail "nerf-render $*"; }
}

# The Blender test split has no w and h: the size given is used, and the
# intrinsics come from its camera_angle_x.
run json --poses "$work/scene/transforms_test.json" --width 12 --height 10 \
  --depth
expect_png "$work/json/r_000.png" 12 10
expect_png "$work/json/r_001.png" 12 10
expect_png "$work/json/depth_001.png" 12 10
expect_png "$work/json/opacity_001.png" 12 10
[ ! -e "$work/json/r_002.png" ] || fail "more frames than poses"
grep -q 'camera path of 2 frames' "$work/json.log" ||
  fail "no camera path line in the log"

# Given w and h, the file's size is the default.
sed 's/^{/{"w": 14, "h": 8, /' "$work/scene/transforms_test.json" \
  >"$work/sized.json"
run sized --poses "$work/sized.json"
expect_png "$work/sized/r_001.png" 14 8

# Two 3 x 4 float32 poses, (2, 3, 4): the identity at (0, 0, 4), and a
# camera at (4, 0, 0) looking back at the origin.  POSIX printf takes
# octal escapes only: 1.0f is 00 00 80 3f, -1.0f 00 00 80 bf, 4.0f
# 00 00 80 40.
z='\000\000\000\000' one='\000\000\200\077' neg='\000\000\200\277'
four='\000\000\200\100'
{
  printf '\223NUMPY\001\000\166\000'
  # The header, padded so that the data starts at byte 128.
  printf '%-117s\n' \
    "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 4), }"
  # The escapes must sit in the format to be decoded.
  # shellcheck disable=SC2059
  printf "$one$z$z$z$z$one$z$z$z$z$one$four"
  # shellcheck disable=SC2059
  printf "$z$z$one$four$z$one$z$z$neg$z$z$z"
} >"$work/path.npy"
[ "$(wc -c <"$work/path.npy")" -eq 224 ] || fail "bad .npy fixture"
run npy --poses "$work/path.npy" --width 16 --height 12 --fov 60
expect_png "$work/npy/r_000.png" 16 12
expect_png "$work/npy/r_001.png" 16 12
[ ! -e "$work/npy/r_002.png" ] || fail "more frames than poses"
# Without a size, 100x100 would be used; a focal alone is enough.
run npy-focal --poses "$work/path.npy" --width 8 --height 8 --focal 9
expect_png "$work/npy-focal/r_001.png" 8 8

# Refusals: a status of 1 and a message naming the file.
refuse() {
  what=$1
  shift
  if $wrap "$render" --model "$work/model.nerf" --out "$work/bad" "$@" \
    2>"$work/bad.log"; then
    fail "nerf-render accepted $what"
  fi
  grep -q "$what" "$work/bad.log" || { cat "$work/bad.log"; fail "$what"; }
}
head -c 100 "$work/path.npy" >"$work/cut.npy"
refuse cut.npy --poses "$work/cut.npy" --width 8 --height 8
printf '{"frames": []}' >"$work/empty.json"
refuse empty.json --poses "$work/empty.json" --width 8 --height 8
refuse missing.json --poses "$work/missing.json"
# Usage errors exit 2.
status=0
$wrap "$render" --model "$work/model.nerf" --out "$work/bad" --poses \
  "$work/path.npy" --width 8 2>/dev/null || status=$?
[ "$status" -eq 2 ] || fail "--width without --height: status $status"
status=0
$wrap "$render" --model "$work/model.nerf" --out "$work/bad" --path orbit \
  --poses "$work/path.npy" 2>/dev/null || status=$?
[ "$status" -eq 2 ] || fail "--path with --poses: status $status"
echo "ok   nerf-render --poses"
