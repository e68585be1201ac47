#!/bin/sh
# nerf-render refuses bad bounds and outputs it cannot hold before it
# renders anything, and shows progress within an image, not only after it.
#
#   test-render-bad-args.sh NERF-SCENE NERF-TRAIN NERF-RENDER
set -eu
scene=$1 train=$2 render=$3
# In a cross build meson names the exe_wrapper (qemu-user) that runs the
# programs; natively it is unset.
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-render-bad.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 1 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training and
# rendering pay for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

# usage WORDS ARGS...: nerf-render exits 2 with WORDS in its message and
# writes no image.
usage() {
  words=$1
  shift
  status=0
  $wrap "$render" --model "$work/model.nerf" --out "$work/bad" --path orbit \
    --frames 1 --width 8 --height 8 "$@" 2>"$work/bad.log" || status=$?
  [ "$status" -eq 2 ] || { cat "$work/bad.log"; fail "$* : status $status"; }
  grep -q -- "$words" "$work/bad.log" || { cat "$work/bad.log"; fail "$*"; }
  [ ! -e "$work/bad/r_000.png" ] || fail "$*: rendered anyway"
}
usage "--near must be less than --far" --near 6 --far 2
usage "--near must be less than --far" --near 3 --far 3
usage "--near must be at least 0" --near -1 --far 2
usage "give --near and --far together" --near 2
usage "give --near and --far together" --far 6
usage "bad value 'inf' for --far" --near 2 --far inf
usage "bad value 'nan' for --near" --near nan --far 6
usage "bad value '1e999' for --far" --near 2 --far 1e999

# Good bounds still render.
$wrap "$render" --model "$work/model.nerf" --out "$work/ok" --path orbit \
  --frames 1 --width 8 --height 8 --near 1 --far 5 2>"$work/ok.log" ||
  { cat "$work/ok.log"; fail "--near 1 --far 5"; }
[ -f "$work/ok/r_000.png" ] || fail "--near 1 --far 5 wrote no image"

# Progress within the one image: without a terminal the first report is a
# line as soon as the first chunk of rays is done.  24x24 is two chunks of
# the renderer's 512 rays, one of them short, so a report comes before the
# last pixel whether one thread renders them or two (few pixels, since
# under qemu each costs tens of milliseconds).
$wrap "$render" --model "$work/model.nerf" --out "$work/progress" --path orbit \
  --frames 1 --width 24 --height 24 2>"$work/progress.log" ||
  { cat "$work/progress.log"; fail "24x24 render"; }
awk -F'[ /]' '/^nerf-render: [0-9]+\/[0-9]+ / && $2 < $3 { ok = 1 }
  END { exit !ok }' "$work/progress.log" ||
  { cat "$work/progress.log"; fail "no progress before the image was done"; }

# An output that cannot be allocated is refused, with its size, before
# rendering: 16384 x 16384 x 3 floats are 3 GiB, more than a 2 GiB address
# space holds.  A sanitizer's shadow memory does not fit in that limit.
# An emulator needs address space of its own, so the case is left out
# there.
if [ -n "$wrap" ]; then
  echo "skip the huge output under $wrap (the emulator needs the address space)"
  echo "ok   nerf-render bad arguments"
  exit 0
fi
status=0
(ulimit -v 2097152 && exec "$render" --model "$work/model.nerf" \
  --out "$work/huge" --path orbit --frames 1 --width 16384 \
  --height 16384) 2>"$work/huge.log" || status=$?
if grep -q Sanitizer "$work/huge.log"; then
  echo "skip the huge output under a sanitizer (it needs the address space)"
else
  [ "$status" -eq 1 ] || { cat "$work/huge.log"; fail "huge: status $status"; }
  grep -q "cannot allocate 3221225472 bytes.*16384x16384" "$work/huge.log" ||
    { cat "$work/huge.log"; fail "huge: no size in the message"; }
  [ ! -e "$work/huge/r_000.png" ] || fail "huge: rendered anyway"
fi
echo "ok   nerf-render bad arguments"
