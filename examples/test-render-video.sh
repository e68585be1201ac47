#!/bin/sh
# shellcheck disable=SC2086 # $wrap is empty or a command to split
# nerf-render --video on a tiny model trained here for two steps: an MP4
# that starts with its 'ftyp' box, beside the PNG frames; with ffprobe, its
# frame count, size and rate; with ffmpeg, its frames match the PNGs.
# Sizes and options it must refuse before rendering anything.  Skipped (77)
# after checking the PNG fallback when the build has no video output.
# Whatever the build, libnerf itself must not need FFmpeg's libraries.
#
#   test-render-video.sh NERF-SCENE NERF-TRAIN NERF-RENDER LIBNERF.so
set -eu
scene=$1 train=$2 render=$3 libnerf=$4
# In a cross build meson names the cross file's exe_wrapper (qemu-user,
# say) that runs the programs; natively it is unset and they run as is.
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-render-video.XXXXXX")
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

# Only nerf-render links FFmpeg: the library's users must not inherit it.
if command -v readelf >/dev/null 2>&1; then
  needed=$(readelf -d "$libnerf" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
  case $needed in
    *libav* | *libsw*) fail "$libnerf needs FFmpeg's libraries:" $needed ;;
  esac
  echo "ok   libnerf needs none of FFmpeg's libraries"
else
  echo "readelf not found: not checking libnerf's dependencies"
fi

# render NAME ARGS...: nerf-render into $work/NAME, stderr in NAME.log;
# its exit status in $status.
render() {
  name=$1
  shift
  status=0
  $wrap "$render" --model "$work/model.nerf" --out "$work/$name" "$@" \
    2>"$work/$name.log" || status=$?
}

render orbit --path orbit --frames 5 --width 16 --height 12 \
  --video "$work/orbit.mp4" --fps 10
if grep -q 'this build has no video output' "$work/orbit.log"; then
  [ "$status" -eq 0 ] || { cat "$work/orbit.log"; fail "exit $status"; }
  [ "$(grep -c 'no video output' "$work/orbit.log")" -eq 1 ] ||
    fail "the no-video line is not said exactly once"
  grep -q "the frames are written as PNG in $work/orbit" "$work/orbit.log" ||
    fail "the no-video line does not name the PNG folder"
  [ -f "$work/orbit/r_004.png" ] || fail "no PNG frames without video"
  [ ! -e "$work/orbit.mp4" ] || fail "a video from a build without video"
  echo "this build has no video output (FFmpeg's libraries were not found" \
       "at build time): checked the PNG fallback only; skipping"
  exit 77
fi
[ "$status" -eq 0 ] || { cat "$work/orbit.log"; fail "--video: exit $status"; }
[ -s "$work/orbit.mp4" ] || fail "orbit.mp4 was not written"
[ ! -e "$work/orbit.mp4.partial" ] || fail "the temporary file was left"
[ -f "$work/orbit/r_004.png" ] || fail "no PNG frames beside the video"
# An MP4 (ISO base media file) opens with a box of type 'ftyp'.
box=$(od -An -c -j4 -N4 "$work/orbit.mp4" | tr -d ' ')
[ "$box" = ftyp ] || fail "orbit.mp4 does not start with an ftyp box ($box)"
grep -q "wrote $work/orbit.mp4: 5 frames of 16x12 at 10 fps" \
  "$work/orbit.log" || { cat "$work/orbit.log"; fail "no 'wrote' line"; }
codec=$(sed -n 's/.* fps, //p' "$work/orbit.log")
echo "ok   --video wrote an MP4 ($codec) and the PNG frames"

# probe FILE: "FRAMES WIDTH HEIGHT RATE" of the first video stream.
probe() {
  ffprobe -v error -count_frames -select_streams v:0 \
    -show_entries stream=nb_read_frames,width,height,r_frame_rate \
    -of default=noprint_wrappers=1 "$1" |
    awk -F= '{ v[$1] = $2 }
             END { print v["nb_read_frames"], v["width"], v["height"],
                   v["r_frame_rate"] }'
}
if command -v ffprobe >/dev/null 2>&1; then
  got=$(probe "$work/orbit.mp4")
  [ "$got" = "5 16 12 10/1" ] ||
    fail "ffprobe: orbit.mp4 has frames, size, rate '$got', expected" \
         "'5 16 12 10/1'"
  render fps30 --path orbit --frames 3 --width 12 --height 8 \
    --video "$work/fps30.mp4"
  [ "$status" -eq 0 ] || { cat "$work/fps30.log"; fail "exit $status"; }
  got=$(probe "$work/fps30.mp4")
  [ "$got" = "3 12 8 30/1" ] ||
    fail "ffprobe: fps30.mp4 has '$got', expected '3 12 8 30/1'"
  echo "ok   ffprobe counts the frames, size and rate asked for"
else
  echo "ffprobe not found: not checking frame count and size"
fi

# The video's frames are the PNGs, in order and in colour: lossy, so
# compared by PSNR (about 40 dB here; a wrong colour model, order or
# row layout gives far less).
if command -v ffmpeg >/dev/null 2>&1; then
  psnr=$(ffmpeg -nostdin -v info -i "$work/orbit.mp4" -framerate 10 \
    -i "$work/orbit/r_%03d.png" -lavfi \
    '[0:v]format=rgb24[a];[1:v]format=rgb24[b];[a][b]psnr' -f null - 2>&1 |
    sed -n 's/.*PSNR.* min:\([0-9.inf]*\).*/\1/p')
  case $psnr in
    inf) ;;
    "") fail "ffmpeg measured no PSNR between orbit.mp4 and the PNGs" ;;
    *) awk -v p="$psnr" 'BEGIN { exit !(p >= 30) }' ||
       fail "orbit.mp4's frames differ from the PNGs: worst PSNR $psnr dB" ;;
  esac
  echo "ok   the video's frames match the PNG frames (worst PSNR $psnr dB)"
else
  echo "ffmpeg not found: not comparing the video's frames with the PNGs"
fi

# Refused before any view is rendered: odd sizes, a folder that does not
# exist for the video, --fps alone.
render odd --path orbit --frames 2 --width 15 --height 12 \
  --video "$work/odd.mp4"
[ "$status" -ne 0 ] || fail "an odd width was accepted for a video"
grep -q 'even width and height' "$work/odd.log" ||
  { cat "$work/odd.log"; fail "no word on the odd width"; }
[ ! -e "$work/odd/r_000.png" ] || fail "rendered before refusing 15x12"
[ ! -e "$work/odd.mp4" ] || fail "a video of an odd width"

render nodir --path orbit --frames 2 --width 16 --height 12 \
  --video "$work/no/such/folder/x.mp4"
[ "$status" -ne 0 ] || fail "a video in a missing folder was accepted"
grep -q "$work/no/such/folder/x.mp4" "$work/nodir.log" ||
  { cat "$work/nodir.log"; fail "the error does not name the video file"; }
[ ! -e "$work/nodir/r_000.png" ] ||
  fail "rendered before finding the video cannot be written"

render fpsalone --path orbit --frames 2 --fps 10
[ "$status" -eq 2 ] || fail "--fps without --video: exit $status, not 2"
grep -q -- '--fps goes with --video' "$work/fpsalone.log" ||
  { cat "$work/fpsalone.log"; fail "no word on --fps alone"; }
render skipping --path orbit --frames 2 --width 16 --height 12 \
  --video "$work/skipping.mp4" --skip-existing
[ "$status" -eq 2 ] || fail "--video with --skip-existing: exit $status, not 2"
grep -q -- 'drop --skip-existing' "$work/skipping.log" ||
  { cat "$work/skipping.log"; fail "no word on --skip-existing"; }
echo "ok   odd sizes, an unwritable video, --fps alone and --video with" \
     "--skip-existing are refused before rendering"
