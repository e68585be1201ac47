#!/bin/sh
# nerf-render --out and nerf-scene --out: a missing folder is created,
# parents too (saying so); a path that cannot be a folder is refused
# before any view is rendered.
#
#   test-out-folder.sh NERF-SCENE NERF-TRAIN NERF-RENDER
set -eu
scene=$1 train=$2 render=$3
# Cross builds run the programs through an emulator (qemu-user).
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-render-out.XXXXXX")
trap 'chmod -R u+w "$work"; rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training and
# rendering pay for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

# render OUT: nerf-render of two small views into OUT; status in $status.
render() {
  status=0
  $wrap "$render" --model "$work/model.nerf" --out "$1" --path orbit --frames 2 \
    --width 8 --height 8 2>"$work/render.log" || status=$?
}

render "$work/new/deeper"
[ "$status" -eq 0 ] || { cat "$work/render.log"; fail "new folder: status"; }
grep -q "created the folder $work/new/deeper\$" "$work/render.log" ||
  { cat "$work/render.log"; fail "new folder: not said"; }
[ -f "$work/new/deeper/r_001.png" ] || fail "new folder: no views"

# refused OUT WORDS: status 1, the message, and no view rendered.
refused() {
  [ "$status" -eq 1 ] || { cat "$work/render.log"; fail "$1: status $status"; }
  grep -q "^nerf-render: $1: cannot be written: $2\$" "$work/render.log" ||
    { cat "$work/render.log"; fail "$1: message"; }
  if grep -q "pixels" "$work/render.log"; then
    cat "$work/render.log"
    fail "$1: rendered before refusing"
  fi
}
: >"$work/a-file"
render "$work/a-file"
refused "$work/a-file" "it is not a folder"
render "$work/a-file/sub"
refused "$work/a-file/sub" "$work/a-file: Not a directory"
if [ "$(id -u)" -eq 0 ]; then
  echo "skip the read-only folder: root may write into any folder"
else
  mkdir "$work/read-only"
  chmod 555 "$work/read-only"
  render "$work/read-only"
  refused "$work/read-only" "Permission denied"
fi

# nerf-scene renders its views before writing them: a file in the way is
# found first.
status=0
$wrap "$scene" --out "$work/a-file" --width 8 --height 8 --train 1 --val 0 \
  --test 0 2>"$work/scene.log" || status=$?
[ "$status" -eq 1 ] || { cat "$work/scene.log"; fail "scene: status $status"; }
grep -q "^nerf-scene: $work/a-file: cannot be written: it is not a folder\$" \
  "$work/scene.log" || { cat "$work/scene.log"; fail "scene: message"; }
if grep -q "wrote" "$work/scene.log"; then
  cat "$work/scene.log"
  fail "scene: rendered before refusing"
fi
$wrap "$scene" --out "$work/new/scene" --width 8 --height 8 --train 1 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; fail "scene"; }
grep -q "created the folder $work/new/scene\$" "$work/scene.log" ||
  { cat "$work/scene.log"; fail "scene: new folder not said"; }
echo "ok   nerf-render --out, nerf-scene --out"
