#!/bin/sh
# nerf-eval leaves the pixels a scene's masks leave out out of its scores,
# says how many, and with --no-masks scores them all.  The built-in scene
# in one transforms.json with occluders (32x32: an SSIM window must fit
# beside the disc): its view 0, painted and masked,
# lands in the test split (every 8th frame), beside view 8, unmasked.
#
#   test-eval-masks.sh NERF-SCENE NERF-TRAIN NERF-EVAL
set -eu
scene=$1 train=$2 eval=$3
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-eval-masks.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 32 --height 32 --train 7 \
  --val 0 --test 2 --layout transforms --occluders \
  2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

$wrap "$eval" --model "$work/model.nerf" --data "$work/scene" --json \
  >"$work/masked.json" 2>/dev/null || fail "nerf-eval"
$wrap "$eval" --model "$work/model.nerf" --data "$work/scene" --json \
  --no-masks >"$work/all.json" 2>/dev/null || fail "nerf-eval --no-masks"
$wrap "$eval" --model "$work/model.nerf" --data "$work/scene" \
  >"$work/masked.txt" 2>/dev/null || fail "nerf-eval (table)"

/usr/bin/python3 - "$work/masked.json" "$work/all.json" <<'PY' ||
import json, sys
masked = json.load(open(sys.argv[1]))
every = json.load(open(sys.argv[2]))
v = masked["per_view"]
w = every["per_view"]
# A disc of radius 6.4 pixels: about 129 of view 0's 1024 pixels.
assert 100 <= v[0]["masked_pixels"] <= 160, v[0]
assert v[1]["masked_pixels"] == 0, v[1]
assert masked["masked_pixels"] == v[0]["masked_pixels"], masked
assert masked["pixels"] == 2 * 1024, masked
assert every["masked_pixels"] == 0 and w[0]["masked_pixels"] == 0, every
# The masked view scores otherwise; the other one exactly as before.
assert v[0]["psnr"] != w[0]["psnr"] and v[0]["ssim"] != w[0]["ssim"], (v, w)
assert v[1]["psnr"] == w[1]["psnr"] and v[1]["ssim"] == w[1]["ssim"], (v, w)
PY
  { cat "$work/masked.json" "$work/all.json"; fail "scores"; }
grep -q "^view   0 .*pixels masked out" "$work/masked.txt" ||
  { cat "$work/masked.txt"; fail "table: view 0 does not say"; }
grep -q "^masks left [0-9]* of 2048 pixels out of the scores" \
  "$work/masked.txt" || { cat "$work/masked.txt"; fail "table: no total"; }
echo "ok"
