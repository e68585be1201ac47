#!/usr/bin/env bash
# nerf-frames, a video's photos (suite data):
#   test-frames.sh PYTHON NERF_FRAMES FFMPEG
# NERF_FRAMES is "" when meson found no FFmpeg libraries: skipped (77);
# FFMPEG "" without the ffmpeg program: the turned video is not tried.
# The videos are YUV4MPEG2 files written here (a header and raw frames,
# which FFmpeg reads without a codec), so that no ffmpeg program is
# needed but for the last part: in each stretch of the video one frame is sharp and the others
# blurred, and the sharp one must be the photo taken.
set -u
python=$1 frames=${2:-} ffmpeg=${3:-}
if [ -z "$frames" ]; then
  echo "SKIP: nerf-frames is not built (FFmpeg's libraries were not found:" \
       "libavformat-dev libavcodec-dev libswscale-dev libavutil-dev)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# write-y4m OUT N SHARP...: N frames of 64x48 noise, each frame's own
# (seeded by its number), blurred but for the frames listed.
cat >"$tmp/y4m.py" <<'EOF'
import sys
import numpy as np
out, n = sys.argv[1], int(sys.argv[2])
sharp = {int(a) for a in sys.argv[3:]}
w, h = 64, 48
with open(out, "wb") as f:
    f.write(b"YUV4MPEG2 W%d H%d F10:1 Ip A1:1 C420jpeg\n" % (w, h))
    for i in range(n):
        rng = np.random.default_rng(i)
        y = rng.integers(0, 256, (h, w)).astype(np.float64)
        if i not in sharp:
            # A 5x5 box blur, as a shaking hand leaves it.
            p = np.pad(y, 2, mode="edge")
            y = sum(p[dy:dy + h, dx:dx + w]
                    for dy in range(5) for dx in range(5)) / 25.0
        f.write(b"FRAME\n")
        f.write(np.clip(y, 0, 255).astype(np.uint8).tobytes())
        f.write(np.full(2 * (w // 2) * (h // 2), 128, np.uint8).tobytes())
EOF

# 12 frames, 4 stretches of 3: the sharp frames are 1, 3, 8 and 10.
"$python" "$tmp/y4m.py" "$tmp/v.y4m" 12 1 3 8 10 || fail "cannot write the video"
list=$("$frames" --video "$tmp/v.y4m" --out "$tmp/p" --frames 4 --list \
       2>"$tmp/err") || { cat "$tmp/err"; fail "nerf-frames failed"; }
chosen=$(echo "$list" | awk '{printf "%s ", $2}')
[ "$chosen" = "1 3 8 10 " ] ||
  fail "the photos are frames $chosen, not the sharp ones 1 3 8 10: $list"
names=$(cd "$tmp/p" && echo *)
[ "$names" = "frame_00000.jpg frame_00001.jpg frame_00002.jpg frame_00003.jpg" ] ||
  fail "photos named $names"
for f in "$tmp"/p/*.jpg; do
  head -c 3 "$f" | od -An -tx1 | grep -q "ff d8 ff" || fail "$f is not a JPEG"
done
grep -q "done in" "$tmp/err" || fail "no progress line: $(cat "$tmp/err")"
echo "ok   the sharpest frame of each stretch, in the video's order"

# Times evenly over the video: 4 photos of 12 frames at 10 a second lie
# in [0, 0.3), [0.3, 0.6), [0.6, 0.9), [0.9, 1.2).
echo "$list" | awk '{ k = NR - 1; if ($3 < 0.3 * k - 1e-6 || $3 >= 0.3 * (k + 1)) exit 1 }' ||
  fail "a photo outside its stretch of time: $list"
echo "ok   one photo per stretch of time"

# Fewer frames than asked: all of them, said.
"$frames" --video "$tmp/v.y4m" --out "$tmp/all" --frames 50 2>"$tmp/err" ||
  { cat "$tmp/err"; fail "--frames 50 of 12 failed"; }
[ "$(ls "$tmp/all" | wc -l)" = 12 ] || fail "--frames 50 of 12 gave $(ls "$tmp/all" | wc -l)"
grep -q "has 12 frames, fewer than --frames 50: taking them all" "$tmp/err" ||
  fail "no word of taking all frames: $(cat "$tmp/err")"
echo "ok   a short video gives all its frames"

# --frames 0, a folder that holds photos, and an empty video stream.
out=$("$frames" --video "$tmp/v.y4m" --out "$tmp/z" --frames 0 2>&1)
rc=$?
[ $rc = 2 ] || fail "--frames 0: exit $rc: $out"
case $out in *"bad value '0' for --frames: expected an integer from 1"*) ;;
  *) fail "--frames 0: $out" ;; esac
[ ! -e "$tmp/z" ] || fail "--frames 0 made the folder"
out=$("$frames" --video "$tmp/v.y4m" --out "$tmp/p" 2>&1)
rc=$?
[ $rc = 2 ] || fail "a folder of photos: exit $rc: $out"
"$python" "$tmp/y4m.py" "$tmp/empty.y4m" 0 || fail "cannot write the empty video"
out=$("$frames" --video "$tmp/empty.y4m" --out "$tmp/e" 2>&1)
rc=$?
[ $rc = 1 ] || fail "no frames: exit $rc: $out"
case $out in *"empty.y4m: has no frames"*) ;; *) fail "no frames: $out" ;; esac
echo "ok   --frames 0, a folder that holds files and a video of no frames refused"

# A video that asks to be turned (as phones store portrait videos): the
# photo stands as FFmpeg's own player shows it.  Needs the ffmpeg program
# (optional) to make the video and decode both for comparison.
if [ -z "$ffmpeg" ]; then
  echo "ok   (turned videos not tried: no ffmpeg program)"
  exit 0
fi
"$ffmpeg" -loglevel error -f rawvideo -pix_fmt yuv420p -s 64x48 -r 10 \
  -i <(tail -c +$(( $(head -1 "$tmp/v.y4m" | wc -c) + 1 )) "$tmp/v.y4m" |
       "$python" -c '
import sys
d = sys.stdin.buffer.read()
frame = 64 * 48 * 3 // 2
step = len(b"FRAME\n") + frame
sys.stdout.buffer.write(b"".join(d[i + 6:i + step]
                                 for i in range(0, len(d), step)))') \
  -c:v libx264 -crf 10 "$tmp/plain.mp4" &&
# The turn is written as the stream is copied (as a phone writes it
# beside frames it does not turn).
"$ffmpeg" -loglevel error -i "$tmp/plain.mp4" -c copy \
  -metadata:s:v:0 rotate=90 "$tmp/turned.mp4" ||
  fail "ffmpeg could not make a turned video"
list=$("$frames" --video "$tmp/turned.mp4" --out "$tmp/t" --frames 1 --list \
       2>"$tmp/err") || { cat "$tmp/err"; fail "nerf-frames on a turned video"; }
k=$(echo "$list" | awk '{print $2}')
"$ffmpeg" -loglevel error -i "$tmp/turned.mp4" -vf "select=eq(n\,$k)" \
  -frames:v 1 -f rawvideo -pix_fmt rgb24 "$tmp/player.rgb" ||
  fail "ffmpeg could not decode the turned video"
"$ffmpeg" -loglevel error -i "$tmp/t/frame_00000.jpg" -f rawvideo \
  -pix_fmt rgb24 "$tmp/photo.rgb" || fail "ffmpeg could not read the photo"
"$python" - "$tmp/player.rgb" "$tmp/photo.rgb" <<'EOF' ||
import sys
import numpy as np
a = np.fromfile(sys.argv[1], np.uint8).astype(float)
b = np.fromfile(sys.argv[2], np.uint8).astype(float)
# The same size (48x64 once turned) and nearly the same pixels: JPEG's
# loss is a few levels on this noise.
ok = a.size == b.size == 48 * 64 * 3 and np.abs(a - b).mean() < 12
print("  photo against the player's frame: %s" %
      ("%.1f levels apart" % np.abs(a - b).mean() if a.size == b.size
       else "sizes differ"))
sys.exit(0 if ok else 1)
EOF
  fail "the turned video's photo does not stand as the player shows it"
grep -q "48x64, turned 270 degrees" "$tmp/err" ||
  fail "no word of the turn: $(cat "$tmp/err")"
echo "ok   a turned video's photos stand as its player shows them"
