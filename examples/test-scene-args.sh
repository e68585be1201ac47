#!/bin/sh
# nerf-scene's --layout and --distortion: one instant-ngp transforms.json
# that records the lens, and clear refusals of what it cannot write.
#
#   test-scene-args.sh NERF-SCENE
set -eu
scene=$1
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-scene-args.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/lens" --width 12 --height 8 --train 3 --val 1 \
  --test 1 --layout transforms --distortion -0.25,0.05,0.001 \
  2>"$work/scene.log" || { cat "$work/scene.log"; fail "transforms layout"; }
json=$work/lens/transforms.json
[ -f "$json" ] || fail "no transforms.json"
[ ! -e "$work/lens/transforms_train.json" ] || fail "wrote the Blender files too"
for key in '"fl_x"' '"w":' '"aabb_scale"' '"k1":	-0.25' '"p1":	0.001' '"k3":	0'; do
  grep -q -- "$key" "$json" || { cat "$json"; fail "no $key"; }
done
[ "$(ls "$work/lens/images" | wc -l)" -eq 5 ] || fail "not 5 images"

# usage WORDS ARGS...: nerf-scene exits 2 with WORDS in its message.
usage() {
  words=$1
  shift
  status=0
  $wrap "$scene" --out "$work/bad" "$@" 2>"$work/bad.log" || status=$?
  [ "$status" -eq 2 ] || { cat "$work/bad.log"; fail "$* : status $status"; }
  grep -q -- "$words" "$work/bad.log" || { cat "$work/bad.log"; fail "$*"; }
  [ ! -e "$work/bad" ] || fail "$*: wrote a scene anyway"
}
usage "--layout needs one of" --layout fisheye
usage "--capture needs one of" --capture indoor
usage "--distortion needs 1 to 5 numbers" --distortion 0.1,x
usage "--distortion needs 1 to 5 numbers" --distortion 1,2,3,4,5,6
usage "--distortion needs 1 to 5 numbers" --distortion ""
# Counts and sizes: the range the library takes, said when refused, and
# stated by --help from the same constants.
usage "bad value '10001' for --train: expected an integer from 1 to 10000" \
  --train 10001
usage "bad value '0' for --train: expected an integer from 1 to 10000" \
  --train 0
usage "bad value '4097' for --width: expected an integer from 8 to 4096" \
  --width 4097
usage "bad value '7' for --height: expected an integer from 8 to 4096" \
  --height 7
usage "an LLFF layout has no validation views" --capture forward --val 2
$wrap "$scene" --help >"$work/help.txt"
for words in "--train N            training views, 1..10000" \
  "image width in pixels, 8..4096" "validation views, 0..10000" \
  "0..10000 (default 16)"; do
  grep -qF -- "$words" "$work/help.txt" ||
    { cat "$work/help.txt"; fail "--help lacks '$words'"; }
done
# --val 0 asks an LLFF layout for what it has: no validation views.
$wrap "$scene" --out "$work/llff" --capture forward --width 8 --height 8 \
  --train 2 --val 0 --test 1 2>"$work/llff.log" ||
  { cat "$work/llff.log"; fail "--capture forward --val 0"; }
[ -f "$work/llff/poses_bounds.npy" ] || fail "--val 0: no LLFF scene"
# An existing scene is not written over unless told: --overwrite.
status=0
$wrap "$scene" --out "$work/llff" --capture forward --width 8 --height 8 \
  --train 2 --test 1 2>"$work/again.log" || status=$?
[ "$status" -eq 2 ] || { cat "$work/again.log"; fail "again: status $status"; }
grep -q "llff holds files already: --overwrite writes" "$work/again.log" ||
  { cat "$work/again.log"; fail "again: message"; }
$wrap "$scene" --out "$work/llff" --capture forward --width 8 --height 8 \
  --train 2 --test 1 --overwrite 2>"$work/again.log" ||
  { cat "$work/again.log"; fail "again with --overwrite"; }

# --capture walk --texture: the walk's train views as a Blender layout,
# each different from the plain scene's (the flag reaches the library).
$wrap "$scene" --out "$work/walk" --capture walk --texture --width 16 \
  --height 12 --train 2 --val 0 --test 0 2>"$work/walk.log" ||
  { cat "$work/walk.log"; fail "--capture walk --texture"; }
$wrap "$scene" --out "$work/walk0" --capture walk --width 16 --height 12 \
  --train 2 --val 0 --test 0 2>"$work/walk.log" ||
  { cat "$work/walk.log"; fail "--capture walk"; }
[ -f "$work/walk/train/r_1.png" ] || fail "--capture walk: no train/r_1.png"
if cmp -s "$work/walk/train/r_1.png" "$work/walk0/train/r_1.png"; then
  fail "--texture changed nothing"
fi
grep -q '"aabb_scale"' "$work/walk/transforms_train.json" ||
  fail "--capture walk: no aabb_scale"

# A lens no camera has: the library says why (status 1).
status=0
$wrap "$scene" --out "$work/bad" --distortion 0,5000 2>"$work/bad.log" ||
  status=$?
[ "$status" -eq 1 ] || fail "--distortion 0,5000: status $status"
grep -q "distortion k2 5000 is beyond" "$work/bad.log" ||
  { cat "$work/bad.log"; fail "--distortion 0,5000: message"; }
echo "ok"
