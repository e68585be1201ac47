#!/usr/bin/env bash
# scripts/colmap-train.sh, photos to a model (suite data):
#   test-colmap-train.sh SCRIPT COMPARE NERF_SCENE NERF_TRAIN [COLMAP]
# COLMAP is the program meson found, or absent.  Always: a missing COLMAP
# is named (exit 3).  With COLMAP: the built-in scene's smooth solids give
# SIFT too few features to match (some 20 a photo), so the reconstruction
# fails and the message must say so.  With NERF_TEST_COLMAP_FERN=1 and fern
# in NERF_DATA_DIR as well (a minute on two cores, so not by default),
# fern's 20 photos reconstruct, agree with poses_bounds.npy and train for
# a step.  Skipped (77) with a message when COLMAP is absent.
set -u
script=$1 compare=$2 scene=$3 train=$4 colmap=${5:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$scene" --out "$tmp/scene" --layout colmap-text --width 200 --height 200 \
  --train 16 --val 0 --test 0 --threads 1 2>/dev/null ||
  fail "nerf-scene could not write the photos"
out=$("$script" --colmap "$tmp/no-such-colmap" "$tmp/scene/images" \
        "$tmp/out0" 2>&1)
rc=$?
[ $rc = 3 ] || fail "missing COLMAP: exit $rc, not 3: $out"
case $out in
  *"COLMAP is not installed"*"apt-get install colmap"*) ;;
  *) fail "missing COLMAP: message '$out'" ;;
esac
echo "ok   a missing COLMAP is named"

if [ -z "$colmap" ]; then
  echo "SKIP: COLMAP is not installed (Debian package colmap), so the" \
       "reconstructions are not tried"
  exit 77
fi
out=$("$script" --colmap "$colmap" --no-train "$tmp/scene/images" \
        "$tmp/out1" 2>&1)
rc=$?
[ $rc = 1 ] || fail "synthetic photos: exit $rc, not 1: $out"
case $out in
  *"could not reconstruct the scene from the 16 photos"*) ;;
  *) fail "synthetic photos: message '$out'" ;;
esac
echo "ok   a failed reconstruction is named"

fern=${NERF_DATA_DIR:-${NERF_DEFAULT_DATA_DIR:-}}/fern
if [ "${NERF_TEST_COLMAP_FERN:-0}" != 1 ]; then
  echo "ok   (fern's reconstruction not tried: NERF_TEST_COLMAP_FERN=1" \
       "asks for it)"
  exit 0
fi
if [ ! -f "$fern/poses_bounds.npy" ] || [ ! -d "$fern/images_8" ]; then
  echo "ok   (fern is not in NERF_DATA_DIR: its reconstruction not tried)"
  exit 0
fi
"$script" --colmap "$colmap" --nerf-train "$train" "$fern/images_8" \
  "$tmp/fern" -- --space ndc --steps 1 --batch 64 2>"$tmp/fern.log" ||
  { cat "$tmp/fern.log"; fail "fern: colmap-train failed"; }
grep -q "forward-facing.*NDC rays" "$tmp/fern.log" ||
  { cat "$tmp/fern.log"; fail "fern: --space ndc did not place it forward-facing"; }
[ -f "$tmp/fern/model.nerf" ] || fail "fern: no model.nerf"
report=$(/usr/bin/python3 "$compare" "$tmp/fern/sparse/0" "$fern") ||
  fail "fern: compare-poses failed"
echo "$report"
echo "$report" | /usr/bin/python3 -c '
import re, sys
text = sys.stdin.read()
rot = float(re.search(r"rotation error \(deg\): mean [0-9.]+, max ([0-9.]+)", text).group(1))
pos = float(re.search(r"position error .*max ([0-9.]+)", text).group(1))
sys.exit(0 if rot < 2.0 and pos < 0.02 else 1)' ||
  fail "fern: COLMAP poses disagree with poses_bounds.npy"
echo "ok   fern: COLMAP poses agree with poses_bounds.npy; one step trained" \
  "in NDC"
