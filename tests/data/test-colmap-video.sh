#!/usr/bin/env bash
# scripts/colmap-train.sh from a video, and photos it cannot place
# explained (suite data):
#   test-colmap-video.sh SCRIPT NERF_SCENE NERF_TRAIN PYTHON NERF_FRAMES \
#                        COLMAP FFMPEG
# NERF_FRAMES, COLMAP and FFMPEG are "" when the build or the machine has
# none: then skipped (77), saying which is missing.
#
# The built-in scene's walk, textured so that SIFT finds features, is
# rendered small (160x120, 40 views, one turn round the solids) and
# encoded by ffmpeg as a video in which each view appears twice, once
# sharp and once blurred (which copy comes first alternates):
#  1. video -> nerf-frames (40 photos, the sharp copies) -> COLMAP with
#     sequential matching -> poses; most photos placed, and one step of
#     nerf-train loads the result;
#  2. a folder of 12 views and two photos unrelated to them (blotchy
#     noise, plain grey): both left out, each named with its reason;
#  3. two stretches of the walk from opposite sides: two reconstructions,
#     the larger kept, and the output says so and why.
set -u
script=$1 scene=$2 train=$3 python=$4 frames=${5:-} colmap=${6:-}
ffmpeg=${7:-}
missing=""
[ -n "$frames" ] || missing="$missing nerf-frames (FFmpeg's -dev libraries)"
[ -n "$colmap" ] || missing="$missing colmap"
[ -n "$ffmpeg" ] || missing="$missing ffmpeg"
if [ -n "$missing" ]; then
  echo "SKIP: not installed or not built:$missing"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
n=40

start=$(date +%s)
"$scene" --out "$tmp/walk" --capture walk --texture --width 160 \
  --height 120 --train $n --val 0 --test 0 --threads 2 2>/dev/null ||
  fail "nerf-scene could not write the walk"
# The blurred copies, then the video's frames in order: view i at frames
# 2i and 2i + 1, the sharp copy first for even i, second for odd i.
"$ffmpeg" -loglevel error -i "$tmp/walk/train/r_%d.png" -vf boxblur=2:1 \
  -start_number 0 "$tmp/walk/blur_%d.png" || fail "ffmpeg could not blur"
mkdir "$tmp/seq"
for ((i = 0; i < n; i++)); do
  sharp=$tmp/walk/train/r_$i.png blurred=$tmp/walk/blur_$i.png
  if [ $((i % 2)) = 0 ]; then a=$sharp b=$blurred; else a=$blurred b=$sharp; fi
  ln -s "$a" "$tmp/seq/$(printf %04d $((2 * i))).png"
  ln -s "$b" "$tmp/seq/$(printf %04d $((2 * i + 1))).png"
done
# A phone's quality, not a streaming service's.
"$ffmpeg" -loglevel error -framerate 20 -i "$tmp/seq/%04d.png" \
  -c:v libx264 -crf 12 -pix_fmt yuv420p "$tmp/walk.mp4" ||
  fail "ffmpeg could not make the video"
echo "ok   a video of $((2 * n)) frames made in $(( $(date +%s) - start )) s"

# 1. From the video to poses, and one training step on them.
start=$(date +%s)
"$script" --colmap "$colmap" --nerf-frames "$frames" --nerf-train "$train" \
  --frames $n --min-registered 1 "$tmp/walk.mp4" "$tmp/out" -- \
  --steps 1 --batch 64 >"$tmp/log" 2>&1 ||
  { cat "$tmp/log"; fail "colmap-train failed on the video"; }
took=$(( $(date +%s) - start ))
grep -q "sequential matching done" "$tmp/log" ||
  { cat "$tmp/log"; fail "the video was not matched sequentially"; }
[ -f "$tmp/out/model.nerf" ] || fail "no model.nerf: the loader or the step failed"
placed=$(sed -n 's/.*COLMAP placed \([0-9]*\) of \([0-9]*\) photos.*/\1 \2/p' \
           "$tmp/log")
read -r got of <<<"$placed"
[ "${of:-0}" = $n ] || { cat "$tmp/log"; fail "$of photos taken, not $n"; }
# Most: at least nine in ten.
[ "${got:-0}" -ge $((n * 9 / 10)) ] ||
  { cat "$tmp/log"; fail "only $got of $of photos placed"; }
# Each photo is the sharp copy of its view: frame 2i for even i, 2i + 1
# for odd i.
awk -v n=$n '{ i = NR - 1; want = 2 * i + (i % 2); if ($2 != want) bad++ }
             END { exit !(NR == n && bad == 0) }' "$tmp/out/frames.txt" ||
  fail "not the sharp frames: $(head -4 "$tmp/out/frames.txt")"
echo "ok   video to poses in $took s: $got of $of photos placed, the sharp" \
  "copies, and nerf-train loads them"

# 2. Photos COLMAP cannot place, each named with its reason: two photos of
# nothing in the scene beside 12 views, blotches of noise (features, but
# none the views share) and a plain grey (no features).
mkdir "$tmp/photos"
for ((i = 0; i < 12; i++)); do
  cp "$tmp/walk/train/r_$i.png" "$tmp/photos/$(printf %02d $i).png"
done
"$python" - "$tmp/photos" <<'EOF' || fail "cannot write the unrelated photos"
import struct, sys, zlib
import numpy as np
w, h = 160, 120
def png(path, px):
    raw = b"".join(b"\0" + px[y].tobytes() for y in range(h))
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data)))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" +
                chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
# Noise on a coarse grid, enlarged 5 times with smooth blending: blobs a
# few pixels across, where SIFT finds its keypoints (pixel noise has
# almost none that survive its smoothing).
g = np.random.default_rng(5).random((h // 5 + 2, w // 5 + 2, 3))
y = np.arange(h) / 5.0
x = np.arange(w) / 5.0
y0, x0 = y.astype(int), x.astype(int)
fy, fx = (y - y0)[:, None, None], (x - x0)[None, :, None]
top = g[y0][:, x0] * (1 - fx) + g[y0][:, x0 + 1] * fx
bottom = g[y0 + 1][:, x0] * (1 - fx) + g[y0 + 1][:, x0 + 1] * fx
blobs = (top * (1 - fy) + bottom * fy) * 255
png(sys.argv[1] + "/05-blobs.png", blobs.astype(np.uint8))
png(sys.argv[1] + "/07-grey.png", np.full((h, w, 3), 128, np.uint8))
EOF
"$script" --colmap "$colmap" --no-train --min-registered 12 "$tmp/photos" \
  "$tmp/out2" >"$tmp/log2" 2>&1 ||
  { cat "$tmp/log2"; fail "colmap-train failed on the folder"; }
grep -v "^colmap-train: \[" "$tmp/log2"
grep -q "exhaustive matching done" "$tmp/log2" ||
  fail "a folder was not matched exhaustively"
grep -q "COLMAP placed 12 of 14 photos" "$tmp/log2" ||
  fail "not 12 of 14 placed"
grep -q "2 photos of 14 not placed" "$tmp/log2" || fail "the count left out"
line=$(grep "  05-blobs.png: " "$tmp/log2") || fail "the blobs are not named"
case $line in
  *" features found; "*" verified inliers with the placed photos"*"none of the placed photos shares 15 or more verified matches"*) ;;
  *) fail "the blobs' reason: $line" ;;
esac
line=$(grep "  07-grey.png: " "$tmp/log2") || fail "the grey is not named"
case $line in
  *"too few features to match"*) ;;
  *) fail "the grey's reason: $line" ;;
esac
# No photo of the walk is named as left out.
if grep -E "^colmap-train:   [0-9]+\.png: " "$tmp/log2"; then
  fail "a placed photo is named as left out"
fi
grep -q "What usually helps: more overlap" "$tmp/log2" ||
  fail "no next step suggested"
echo "ok   photos COLMAP cannot place are named, each with its reason"

# 3. Two stretches of the walk from opposite sides of the solids, 12 views
# and 10 (the mapper keeps no reconstruction of fewer), which share
# nothing: COLMAP makes two reconstructions, and the output says which it
# kept and why, and where the other photos went.
mkdir "$tmp/apart"
for i in 0 1 2 3 4 5 6 7 8 9 10 11 20 21 22 23 24 25 26 27 28 29; do
  cp "$tmp/walk/train/r_$i.png" "$tmp/apart/$(printf %02d $i).png"
done
"$script" --colmap "$colmap" --no-train --min-registered 10 "$tmp/apart" \
  "$tmp/out3" >"$tmp/log3" 2>&1 ||
  { cat "$tmp/log3"; fail "colmap-train failed on two stretches"; }
grep -v "^colmap-train: \[" "$tmp/log3"
grep -q "COLMAP made 2 separate reconstructions: [01] (12 photos), [01] (10 photos); kept [01], which has the most photos registered" "$tmp/log3" ||
  fail "the reconstructions and the one kept are not said"
grep -q "COLMAP placed 12 of 22 photos" "$tmp/log3" || fail "not 12 of 22 placed"
for i in 20 21 22 23 24 25 26 27 28 29; do
  grep -q "  $i.png: .*placed in reconstruction [01] instead, which was not joined" \
    "$tmp/log3" || fail "$i.png is not said to be in the other reconstruction"
done
# The loader's sparse/0 is the larger.
[ "$(od -An -t u8 -N 8 "$tmp/out3/sparse/0/images.bin" | tr -d ' ')" = 12 ] ||
  fail "sparse/0 is not the reconstruction of 12 photos"
echo "ok   of two reconstructions the larger is kept, and the output says why"
