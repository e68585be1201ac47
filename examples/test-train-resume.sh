#!/bin/sh
# nerf-train on an existing MODEL: refused without --resume or --overwrite
# (nothing trained, MODEL untouched); --overwrite replaces it; --resume
# continues it, but not with another --preset, and warns when the data is
# not what MODEL was trained on.  The batch: MODEL records it, --resume
# keeps it unless --batch is given, and another is warned about; the fast
# preset's default is 2048 rays of at most 131072 samples.
#
#   test-train-resume.sh NERF-SCENE NERF-TRAIN NERF-INFO
set -eu
scene=$1 train=$2 info=$3

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-train-resume.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

"$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }

# run LOG ARGS...: nerf-train on the scene into model.nerf; status in $status.
run() {
  log=$1
  shift
  status=0
  "$train" --data "$work/scene" --out "$work/model.nerf" --batch 64 "$@" \
    2>"$work/$log" || status=$?
}
# refused LOG WORDS: status 2, one line saying WORDS, nothing trained and
# model.nerf as it was.
refused() {
  [ "$status" -eq 2 ] || { cat "$work/$1"; fail "$1: status $status"; }
  grep -q -- "$2" "$work/$1" || { cat "$work/$1"; fail "$1: message"; }
  [ "$(wc -l <"$work/$1")" -eq 1 ] || { cat "$work/$1"; fail "$1: not one line"; }
  cmp -s "$work/model.nerf" "$work/first.nerf" ||
    fail "$1: model.nerf was changed"
}

run first.log --steps 2
[ "$status" -eq 0 ] || { cat "$work/first.log"; fail "first run"; }
cp "$work/model.nerf" "$work/first.nerf"

run again.log --steps 3
refused again.log \
  "model.nerf exists: --resume continues it, --overwrite replaces it"

run both.log --steps 3 --resume --overwrite
[ "$status" -eq 2 ] || { cat "$work/both.log"; fail "both: status $status"; }
grep -q "give one" "$work/both.log" || { cat "$work/both.log"; fail "both"; }

# tiny is the default preset; fast is another network.
run preset.log --steps 3 --resume --preset fast
refused preset.log "model of the tiny preset, not of --preset fast"
run same-preset.log --steps 3 --resume --preset tiny
[ "$status" -eq 0 ] || { cat "$work/same-preset.log"; fail "same preset"; }
grep -q "resuming $work/model.nerf at step 2" "$work/same-preset.log" ||
  { cat "$work/same-preset.log"; fail "same preset: not resumed"; }

grep -q "other data" "$work/same-preset.log" &&
  { cat "$work/same-preset.log"; fail "same data: warned"; }

# Other data: more and larger images; images of the same number and size
# that show another scene.
other() {
  "$scene" --out "$work/$1" --width "$2" --height "$2" --train "$3" \
    --val 0 --test 0 $4 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
  status=0
  "$train" --data "$work/$1" --out "$work/model.nerf" --batch 64 --resume \
    --steps 100000000 --seconds 0.1 2>"$work/$1.log" || status=$?
  [ "$status" -eq 0 ] || { cat "$work/$1.log"; fail "$1: status $status"; }
}
other larger 24 6 ""
grep -q "^nerf-train: trainer: the model was trained on other data than this dataset (image count, image size differ): it was trained on 4 images of 16x16 (blender, .*), this dataset has 6 of 24x24 (blender, " \
  "$work/larger.log" || { cat "$work/larger.log"; fail "larger: warning"; }
run same-again.log --steps 100000000 --seconds 0.1 --resume
grep -q "trained on 6 images of 24x24" "$work/same-again.log" ||
  { cat "$work/same-again.log"; fail "the last data trained on is not kept"; }
# (model.nerf was last trained on scene: 4 images of 16x16.)
other unbounded 16 4 "--capture unbounded"
grep -q "(mean colour, near/far bounds differ): it was trained on 4 images of 16x16 (blender, .*), this dataset has 4 of 16x16 (blender, " \
  "$work/unbounded.log" ||
  { cat "$work/unbounded.log"; fail "unbounded: warning"; }

run overwrite.log --steps 1 --overwrite
[ "$status" -eq 0 ] || { cat "$work/overwrite.log"; fail "overwrite"; }
grep -q "step 1, .*saved $work/model.nerf" "$work/overwrite.log" ||
  { cat "$work/overwrite.log"; fail "overwrite: not a new model"; }

# batch MODEL: the rays and samples a step nerf-info says MODEL records.
batch() {
  "$info" "$work/$1" | sed -n 's/^batch *rays \([0-9]*\), samples \([0-9]*\)$/\1 \2/p'
}
# (model.nerf: --batch 64 --steps 1 --overwrite above.)
[ "$(batch model.nerf)" = "64 0" ] || fail "batch not recorded: $(batch model.nerf)"
# resume LOG STEPS ARGS...: --resume model.nerf to STEPS.
resume() {
  log=$1 steps=$2
  shift 2
  "$train" --data "$work/scene" --out "$work/model.nerf" --steps "$steps" \
    --resume "$@" 2>"$work/$log" || { cat "$work/$log"; fail "$log: status"; }
}
resume keep.log 2
grep -q "^nerf-train: 64 rays a step, as $work/model.nerf was trained" \
  "$work/keep.log" || { cat "$work/keep.log"; fail "keep: batch not kept"; }
grep -q "trained at" "$work/keep.log" && { cat "$work/keep.log"; fail "keep: warned"; }
resume other-batch.log 3 --batch 32 --batch-samples 500
grep -q "^nerf-train: trainer: the model was trained at 64 rays a step (batch_samples 0) and this trainer takes 32 (batch_samples 500)" \
  "$work/other-batch.log" || { cat "$work/other-batch.log"; fail "other batch: no warning"; }
[ "$(batch model.nerf)" = "32 500" ] || fail "other batch: $(batch model.nerf)"
resume keep-both.log 4
grep -q "up to 32 rays of 500 samples per step" "$work/keep-both.log" ||
  { cat "$work/keep-both.log"; fail "keep both: trainer's batch"; }
grep -q "trained at" "$work/keep-both.log" &&
  { cat "$work/keep-both.log"; fail "keep both: warned"; }
# A new model of the fast preset: 2048 rays of at most 131072 samples a
# step unless told; a --batch of its own is taken whole.
"$train" --data "$work/scene" --out "$work/fast.nerf" --preset fast --steps 1 \
  --checkpoint-every 0 2>"$work/fast.log" ||
  { cat "$work/fast.log"; fail "fast: status"; }
[ "$(batch fast.nerf)" = "2048 131072" ] || fail "fast: $(batch fast.nerf)"
"$train" --data "$work/scene" --out "$work/fast.nerf" --preset fast --steps 1 \
  --checkpoint-every 0 --batch 512 --overwrite 2>"$work/fast512.log" ||
  { cat "$work/fast512.log"; fail "fast 512: status"; }
[ "$(batch fast.nerf)" = "512 0" ] || fail "fast 512: $(batch fast.nerf)"
echo "ok   nerf-train on an existing model"
