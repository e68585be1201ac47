#!/bin/sh
# nerf-train on an existing MODEL: refused without --resume or --overwrite
# (nothing trained, MODEL untouched); --overwrite replaces it; --resume
# continues it, but not with another --preset.
#
#   test-train-resume.sh NERF-SCENE NERF-TRAIN
set -eu
scene=$1 train=$2

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

run overwrite.log --steps 1 --overwrite
[ "$status" -eq 0 ] || { cat "$work/overwrite.log"; fail "overwrite"; }
grep -q "step 1, .*saved $work/model.nerf" "$work/overwrite.log" ||
  { cat "$work/overwrite.log"; fail "overwrite: not a new model"; }
echo "ok   nerf-train on an existing model"
