#!/bin/sh
# nerf-export depth and points on the built-in scene after a few training
# steps: the arrays and files are there with the right shapes and types,
# the depths agree with each other and the rays, the cap and the format
# options hold, and bad arguments exit 2 (or 1 for an output that cannot
# be written) before anything is rendered.
#
#   test-export-views.sh NERF-SCENE NERF-TRAIN NERF-EXPORT [PYTHON3]
set -eu
scene=$1 train=$2 export=$3 python=${4:-}
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-export-views.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 16 --height 12 --train 3 --val 0 \
  --test 2 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training and
# rendering pay for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 3 \
  --batch 64 --preset tiny --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

# depth: three arrays and two previews a test view.
$wrap "$export" depth --model "$work/model.nerf" --data "$work/scene" \
  --out "$work/depth" 2>"$work/depth.log" || { cat "$work/depth.log"; exit 1; }
for v in 000 001; do
  for kind in distance zdepth opacity; do
    [ -s "$work/depth/${v}_$kind.npy" ] || fail "no ${v}_$kind.npy"
  done
  for kind in depth opacity; do
    [ -s "$work/depth/${v}_$kind.png" ] || fail "no ${v}_$kind.png"
  done
done
[ ! -e "$work/depth/002_zdepth.npy" ] || fail "a third test view"
# float32, 12 x 16: a 128-byte header and 768 bytes of data.
size=$(wc -c <"$work/depth/000_zdepth.npy")
[ "$size" -eq 896 ] || fail "000_zdepth.npy has $size bytes, not 896"
head -c 128 "$work/depth/000_zdepth.npy" | grep -q "'descr': '<f4'" ||
  fail "000_zdepth.npy is not float32"
head -c 128 "$work/depth/000_zdepth.npy" | grep -q "'shape': (12, 16)" ||
  fail "000_zdepth.npy is not 12 x 16"

# --skip names the views as in the split; --no-png writes arrays only.
$wrap "$export" depth --model "$work/model.nerf" --data "$work/scene" \
  --out "$work/depth2" --skip 2 --split train --no-png 2>"$work/depth2.log" ||
  { cat "$work/depth2.log"; exit 1; }
[ -s "$work/depth2/000_distance.npy" ] && [ -s "$work/depth2/002_distance.npy" ] ||
  fail "--skip 2: views 000 and 002 expected"
[ ! -e "$work/depth2/001_distance.npy" ] || fail "--skip 2 wrote view 001"
[ ! -e "$work/depth2/000_depth.png" ] || fail "--no-png wrote a preview"

if [ -n "$python" ] && "$python" -c "import numpy" 2>/dev/null; then
  "$python" - "$work/depth" <<'PY' || fail "depth arrays disagree"
import sys, numpy as np
d = sys.argv[1]
for v in ("000", "001"):
    dist = np.load("%s/%s_distance.npy" % (d, v))
    z = np.load("%s/%s_zdepth.npy" % (d, v))
    op = np.load("%s/%s_opacity.npy" % (d, v))
    assert dist.dtype == np.float32 and dist.shape == (12, 16), dist.shape
    assert np.all((op >= 0) & (op <= 1 + 1e-6)), "opacity out of [0, 1]"
    seen = op > 0
    assert seen.any(), "no pixel sees anything"
    assert np.all(z[~seen] == 0) and np.all(dist[~seen] == 0)
    # distance = z |d|, |d| >= 1 (the camera-space z of d is -1) and
    # largest in the corners.
    ratio = dist[seen] / z[seen]
    assert np.all(ratio >= 1 - 1e-6), ratio.min()
    assert np.all(ratio < 1.5), ratio.max()
    # The scene's sampler range (the dataset's near and far) bounds z.
    assert np.all((z[seen] >= 2 - 1e-3) & (z[seen] <= 6 + 1e-3)), \
        (z[seen].min(), z[seen].max())
print("depth arrays agree")
PY
else
  echo "note: no python3 with numpy: the depth arrays' values are not checked"
fi

# --poses: the cameras of a file (here two, 10 x 8), numbered in it; no
# --data needed (the model's recorded settings serve).
cat >"$work/poses.json" <<'JSON'
{"camera_angle_x": 0.6911, "w": 10, "h": 8, "frames": [
 {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]},
 {"transform_matrix": [[1,0,0,0],[0,0,-1,-4],[0,1,0,0],[0,0,0,1]]}]}
JSON
$wrap "$export" depth --model "$work/model.nerf" --poses "$work/poses.json" \
  --out "$work/depth3" --no-png 2>"$work/depth3.log" ||
  { cat "$work/depth3.log"; exit 1; }
head -c 128 "$work/depth3/001_distance.npy" | grep -q "'shape': (8, 10)" ||
  fail "--poses: 001_distance.npy is not 8 x 10"
[ ! -e "$work/depth3/002_distance.npy" ] || fail "--poses: a third view"
$wrap "$export" points --model "$work/model.nerf" --poses "$work/poses.json" \
  --data "$work/scene" --opacity 0 --out "$work/poses.ply" \
  2>"$work/points3.log" || { cat "$work/points3.log"; exit 1; }
grep -q "points from 2 views" "$work/points3.log" ||
  { cat "$work/points3.log"; fail "--poses: not the file's 2 views"; }

# points: a capped binary cloud, then ASCII.
$wrap "$export" points --model "$work/model.nerf" --data "$work/scene" \
  --out "$work/pc/cloud.ply" --max-points 50 --opacity 0.1 \
  2>"$work/points.log" || { cat "$work/points.log"; exit 1; }
head -c 400 "$work/pc/cloud.ply" | grep -aq "^format binary_little_endian 1.0" ||
  fail "not a binary PLY"
count=$(head -c 400 "$work/pc/cloud.ply" | grep -a "^element vertex" |
        cut -d' ' -f3)
[ "$count" -ge 1 ] && [ "$count" -le 50 ] || fail "$count points, cap 50"
header=$(head -c 400 "$work/pc/cloud.ply" | sed -n '1,/^end_header$/p' | wc -c)
size=$(wc -c <"$work/pc/cloud.ply")
[ "$size" -eq $((header + 27 * count)) ] ||
  fail "$size bytes for $count points after a $header-byte header"
$wrap "$export" points --model "$work/model.nerf" --data "$work/scene" \
  --out "$work/cloud.ply" --ascii --stride 2 --opacity 0 \
  2>"$work/points2.log" || { cat "$work/points2.log"; exit 1; }
count=$(grep -a "^element vertex" "$work/cloud.ply" | cut -d' ' -f3)
lines=$(sed -n '/^end_header$/,$p' "$work/cloud.ply" | wc -l)
[ "$lines" -eq $((count + 1)) ] || fail "ASCII: $lines lines for $count"
# Stride 2 on 3 views of 16 x 12: at most 3 x 8 x 6 rays.
[ "$count" -ge 1 ] && [ "$count" -le 144 ] || fail "stride 2: $count points"
grep -q "points from 3 views" "$work/points2.log" ||
  { cat "$work/points2.log"; fail "no summary line"; }

# usage STATUS WORDS ARGS...: nerf-export exits STATUS with WORDS in its
# message and writes no cloud.
usage() {
  want=$1 words=$2
  shift 2
  status=0
  $wrap "$export" "$@" 2>"$work/bad.log" || status=$?
  [ "$status" -eq "$want" ] ||
    { cat "$work/bad.log"; fail "$* : status $status, not $want"; }
  grep -q -- "$words" "$work/bad.log" || { cat "$work/bad.log"; fail "$*"; }
  [ ! -e "$work/bad.ply" ] || fail "$*: wrote a cloud anyway"
}
m="--model $work/model.nerf --data $work/scene"
usage 2 "bad value '0' for --stride" points $m --out "$work/bad.ply" --stride 0
usage 2 "bad value '1.5' for --opacity" points $m --out "$work/bad.ply" \
  --opacity 1.5
usage 2 "bad value '0' for --max-points" points $m --out "$work/bad.ply" \
  --max-points 0
usage 2 "did you mean --stride" points $m --out "$work/bad.ply" --strid 2
usage 2 "--model, --out and --data or --poses are required" points \
  --model "$work/model.nerf" --out "$work/bad.ply"
usage 2 "with --poses they would change nothing" points $m \
  --poses "$work/poses.json" --split test --out "$work/bad.ply"
usage 2 "did you mean points" pionts $m --out "$work/bad.ply"
usage 2 "a subcommand is required"
usage 2 "did you mean --skip" depth $m --out "$work/bad" --skp 2
usage 2 "unknown option '--ascii'" depth $m --out "$work/bad" --ascii
usage 1 "cannot be written" points $m --out "$work/cloud.ply/x.ply"
usage 1 "cannot be written" depth $m --out "$work/cloud.ply/d"
[ ! -e "$work/bad" ] || fail "a refused depth run made its folder"

# --help: usage, options with defaults, examples; exit 0 on stdout alone.
for sub in depth points; do
  $wrap "$export" $sub --help >"$work/help" 2>"$work/err" ||
    fail "$sub --help: status $?"
  [ ! -s "$work/err" ] || fail "$sub --help wrote to stderr"
  grep -q "^usage: nerf-export $sub" "$work/help" || fail "$sub: no usage"
  grep -q "^  nerf-export $sub" "$work/help" || fail "$sub: no example"
done
$wrap "$export" --help | grep -q "points" || fail "nerf-export --help"
echo "ok: nerf-export depth and points"
