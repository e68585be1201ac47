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

# An existing model is replaced only when asked, and refused before any
# COLMAP stage runs (the stand-in COLMAP would fail if it ran).
mkdir -p "$tmp/out2" && : >"$tmp/out2/model.nerf"
out=$("$script" --colmap false "$tmp/scene/images" "$tmp/out2" 2>&1)
rc=$?
[ $rc = 2 ] || fail "existing model: exit $rc, not 2: $out"
case $out in
  *"model.nerf exists: add -- --overwrite"*) ;;
  *) fail "existing model: message '$out'" ;;
esac
echo "ok   an existing model is not replaced unasked"

# Bad arguments of the video way in, refused before anything runs (the
# stand-in COLMAP, true, would do nothing).
bad() {
  local words=$1
  shift
  out=$("$script" --colmap true "$@" 2>&1)
  rc=$?
  [ $rc = 2 ] || fail "$*: exit $rc, not 2: $out"
  case $out in *"$words"*) ;; *) fail "$*: message '$out'" ;; esac
}
bad "--frames needs a whole number of photos above 0, not '0'" \
  --frames 0 "$tmp/scene/images" "$tmp/out3"
bad "--matcher must be exhaustive or sequential, not 'vocab'" \
  --matcher vocab "$tmp/scene/images" "$tmp/out3"
bad "$tmp/none.mp4: neither a folder of photos nor a video file" \
  "$tmp/none.mp4" "$tmp/out3"
[ ! -e "$tmp/out3" ] || fail "a refused run made its OUT_DIR"
echo "ok   --frames 0, an unknown --matcher and a missing video refused"

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
