#!/bin/sh
# nerf-eval and nerf-render --march-steps N: a marching model rendered in
# N steps of its grid's diagonal instead of its recorded ones.  The
# recorded N given again changes nothing; another N changes the images;
# out-of-range values and a model that does not march are refused.
# nerf-train --render-march-steps N: what a model records (1280 unless
# given) changes how it renders, not how it trains, and a resumed run
# trains in the same 1024 steps as an unbroken one.
#
#   test-march-steps.sh NERF-SCENE NERF-TRAIN NERF-EVAL NERF-RENDER
set -eu
scene=$1 train=$2 eval=$3 render=$4
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-march-steps.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 12 --height 12 --train 8 --val 0 \
  --test 3 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# Two steps: a new model has density everywhere in its grid, so the
# spacing of a ray's samples already shows in every view, and a longer
# run would only cost time (most of all under qemu).
$wrap "$train" --data "$work/scene" --out "$work/fast.nerf" --preset fast \
  --steps 2 --batch 64 --checkpoint-every 0 2>"$work/train.log" ||
  { cat "$work/train.log"; exit 1; }

scores() { # NAME MODEL [FLAGS]: the per-view lines of nerf-eval
  name=$1 model=$2
  shift 2
  $wrap "$eval" --model "$work/$model" --data "$work/scene" "$@" \
    >"$work/$name.txt" 2>"$work/$name.log" ||
    { cat "$work/$name.log"; fail "nerf-eval $*"; }
  grep "^view" "$work/$name.txt" >"$work/$name.views"
}
scores recorded fast.nerf
scores same fast.nerf --march-steps 1280
scores finer fast.nerf --march-steps 4096
cmp -s "$work/recorded.views" "$work/same.views" ||
  { cat "$work/recorded.views" "$work/same.views"; fail "1280 changed them"; }
cmp -s "$work/recorded.views" "$work/finer.views" &&
  { cat "$work/finer.views"; fail "4096 scored as 1280"; }
echo "ok   nerf-eval --march-steps"

# The same training, another record: fast.nerf in 1024 steps is it.
$wrap "$train" --data "$work/scene" --out "$work/r1024.nerf" --preset fast \
  --steps 2 --batch 64 --checkpoint-every 0 --render-march-steps 1024 \
  2>"$work/r1024.log" || { cat "$work/r1024.log"; exit 1; }
scores trained fast.nerf --march-steps 1024
scores r1024 r1024.nerf
cmp -s "$work/trained.views" "$work/r1024.views" ||
  { cat "$work/trained.views" "$work/r1024.views"
    fail "--render-march-steps 1024: not fast.nerf in 1024 steps"; }
cmp -s "$work/recorded.views" "$work/r1024.views" &&
  fail "--render-march-steps 1024 recorded 1280"
# One step recording 1280, one recording 1024, each resumed for one
# more: both train the second in 1024 steps, as the first.
for r in 1280 1024; do
  $wrap "$train" --data "$work/scene" --out "$work/resumed$r.nerf" \
    --preset fast --steps 1 --batch 64 --checkpoint-every 0 \
    --render-march-steps $r 2>"$work/resume$r.log" &&
  $wrap "$train" --data "$work/scene" --out "$work/resumed$r.nerf" \
    --preset fast --steps 2 --batch 64 --checkpoint-every 0 --resume \
    2>>"$work/resume$r.log" || { cat "$work/resume$r.log"; exit 1; }
done
cmp -s "$work/resumed1280.nerf" "$work/resumed1024.nerf" ||
  fail "a resumed run trained in the steps its model records"
echo "ok   nerf-train --render-march-steps"

$wrap "$render" --model "$work/fast.nerf" --out "$work/r1" --path orbit \
  --frames 1 --width 12 --height 12 >/dev/null 2>"$work/r1.log" ||
  { cat "$work/r1.log"; fail "nerf-render"; }
$wrap "$render" --model "$work/fast.nerf" --out "$work/r4" --path orbit \
  --frames 1 --width 12 --height 12 --march-steps 4096 >/dev/null \
  2>"$work/r4.log" || { cat "$work/r4.log"; fail "nerf-render --march-steps"; }
cmp -s "$work/r1/r_000.png" "$work/r4/r_000.png" &&
  fail "nerf-render --march-steps 4096 drew the recorded march's image"
echo "ok   nerf-render --march-steps"

refused() { # STATUS PATTERN PROGRAM FLAGS...: exits STATUS, says PATTERN
  status=$1 pattern=$2
  shift 2
  rc=0
  $wrap "$@" >/dev/null 2>"$work/refused.log" || rc=$?
  [ "$rc" = "$status" ] ||
    { cat "$work/refused.log"; fail "$*: status $rc, not $status"; }
  grep -q "$pattern" "$work/refused.log" ||
    { cat "$work/refused.log"; fail "$*: no '$pattern'"; }
}
for n in 0 65537 x; do
  refused 2 "bad value '$n' for --render-march-steps" "$train" \
    --data "$work/scene" --out "$work/bad.nerf" --preset fast \
    --render-march-steps "$n"
  refused 2 "bad value '$n' for --march-steps" "$eval" \
    --model "$work/fast.nerf" --data "$work/scene" --march-steps "$n"
  refused 2 "bad value '$n' for --march-steps" "$render" \
    --model "$work/fast.nerf" --out "$work/bad" --path orbit --march-steps "$n"
done
# The tiny preset samples in bins; it has no occupancy grid to march.
$wrap "$train" --data "$work/scene" --out "$work/tiny.nerf" --steps 1 \
  --batch 16 --coarse-samples 4 --fine-samples 4 2>"$work/tiny.log" ||
  { cat "$work/tiny.log"; exit 1; }
refused 1 "occupancy grid" "$eval" --model "$work/tiny.nerf" \
  --data "$work/scene" --march-steps 2048
refused 2 "without marching" "$train" --data "$work/scene" \
  --out "$work/tiny2.nerf" --steps 1 --render-march-steps 2048
[ -e "$work/tiny2.nerf" ] && fail "a refused --render-march-steps trained"
echo "ok   refused values and models"
