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
# A lens no camera has: the library says why (status 1).
status=0
$wrap "$scene" --out "$work/bad" --distortion 0,5000 2>"$work/bad.log" ||
  status=$?
[ "$status" -eq 1 ] || fail "--distortion 0,5000: status $status"
grep -q "distortion k2 5000 is beyond" "$work/bad.log" ||
  { cat "$work/bad.log"; fail "--distortion 0,5000: message"; }
echo "ok"
