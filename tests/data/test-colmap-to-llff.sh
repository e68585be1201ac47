#!/usr/bin/env bash
# scripts/colmap-to-llff.py (suite data): the built-in scene's
# forward-facing capture written as a COLMAP model, turned into LLFF's
# poses_bounds.npy, loads as an LLFF scene and gives back COLMAP's poses
# (scripts/compare-poses.py: the same cameras up to a similarity, to
# rounding).  Skipped (77) without NumPy.
#   test-colmap-to-llff.sh TO_LLFF COMPARE NERF_SCENE NERF_TRAIN
set -u
to_llff=$1 compare=$2 scene=$3 train=$4
py=/usr/bin/python3
"$py" -c 'import numpy' 2>/dev/null ||
  { echo "SKIP: $py has no NumPy (apt-get install python3-numpy)"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$scene" --out "$tmp/colmap" --capture forward --layout colmap-binary \
  --width 40 --height 30 --train 16 --val 0 --test 0 --threads 1 \
  2>/dev/null || fail "nerf-scene could not write the COLMAP model"
mkdir "$tmp/llff"
ln -s "$tmp/colmap/images" "$tmp/llff/images"
"$py" "$to_llff" "$tmp/colmap/sparse/0" "$tmp/llff/poses_bounds.npy" ||
  fail "colmap-to-llff.py failed"
out=$("$py" "$compare" "$tmp/colmap/sparse/0" "$tmp/llff" 2>&1) ||
  fail "compare-poses.py: $out"
echo "$out"
rot=$(echo "$out" | sed -n 's/^rotation error (deg): mean \([0-9.e-]*\).*/\1/p')
pos=$(echo "$out" | sed -n 's/^position error .*: mean \([0-9.e-]*\).*/\1/p')
"$py" -c "import sys; sys.exit(0 if float('$rot') < 1e-3 and float('$pos') < 1e-5 else 1)" ||
  fail "the LLFF poses are not COLMAP's: rotation $rot deg, position $pos"
log=$("$train" --data "$tmp/llff" --steps 1 --checkpoint-every 0 \
        --out "$tmp/m.nerf" 2>&1) || fail "nerf-train: $log"
case $log in
  *"LLFF scene, 14 of 16 images"*) ;;
  *) fail "not loaded as LLFF with every 8th held out: $log" ;;
esac
echo "ok"
