#!/bin/sh
# nerf-eval --skip K numbers its views by their index in the split (0, K,
# 2K, ...), in the table and in --json, with the scores of those views.
#
#   test-eval-skip.sh NERF-SCENE NERF-TRAIN NERF-EVAL
set -eu
scene=$1 train=$2 eval=$3
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-eval-skip.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# 12x12, a little more than SSIM's 11x11 window (under qemu each
# pixel's render costs tens of milliseconds).
$wrap "$scene" --out "$work/scene" --width 12 --height 12 --train 4 --val 0 \
  --test 7 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training and
# rendering pay for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

$wrap "$eval" --model "$work/model.nerf" --data "$work/scene" \
  >"$work/all.txt" 2>/dev/null || fail "nerf-eval"
$wrap "$eval" --model "$work/model.nerf" --data "$work/scene" --skip 3 \
  >"$work/skip.txt" 2>/dev/null || fail "nerf-eval --skip 3"
views=$(awk '$1 == "view" { printf "%s ", $2 }' "$work/skip.txt")
[ "$views" = "0 3 6 " ] || { cat "$work/skip.txt"; fail "views: $views"; }
# Each is the same view as in a full run, with the same scores.
grep "^view" "$work/skip.txt" | while read -r line; do
  grep -qxF "$line" "$work/all.txt" ||
    { cat "$work/all.txt"; fail "'$line' is not that view of the split"; }
done
$wrap "$eval" --model "$work/model.nerf" --data "$work/scene" --skip 3 \
  --json >"$work/skip.json" 2>/dev/null || fail "nerf-eval --skip 3 --json"
tr '{' '\n' <"$work/skip.json" | sed -n 's/^"view":\([0-9]*\),.*/\1/p' |
  tr '\n' ' ' >"$work/json-views"
[ "$(cat "$work/json-views")" = "0 3 6 " ] ||
  { cat "$work/skip.json"; fail "--json views: $(cat "$work/json-views")"; }
echo "ok"
