#!/bin/sh
# A mistyped option or a bad value costs the user one line, not a page:
# every program exits 2 with a single line on stderr that names the
# option (and the nearest real one) and points to --help, and does no work.
#
#   test-cli-errors.sh NERF-SCENE NERF-TRAIN NERF-RENDER NERF-EVAL NERF-INFO
#                      [NERF-VIEWER]
set -eu
scene=$1 train=$2 render=$3 eval=$4 info=$5 viewer=${6:-}
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-cli-errors.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# one PROGRAM WORDS ARGS...: PROGRAM exits 2 with exactly one line on
# stderr, containing WORDS, and nothing on stdout.
one() {
  prog=$1 words=$2
  shift 2
  name=$(basename "$prog")
  status=0
  $wrap "$prog" "$@" >"$work/out" 2>"$work/err" || status=$?
  [ "$status" -eq 2 ] || { cat "$work/err"; fail "$name $*: status $status"; }
  lines=$(wc -l <"$work/err")
  [ "$lines" -eq 1 ] || { cat "$work/err"; fail "$name $*: $lines lines"; }
  grep -qF -- "$words" "$work/err" ||
    { cat "$work/err"; fail "$name $*: no '$words'"; }
  grep -qF -- "$name --help lists the options" "$work/err" ||
    { cat "$work/err"; fail "$name $*: no pointer to --help"; }
  [ ! -s "$work/out" ] || { cat "$work/out"; fail "$name $*: stdout"; }
}

one "$train" "unknown option '--step' (did you mean --steps?)" \
  --data "$work/none" --out "$work/m.nerf" --step 5
one "$train" "did you mean --steps?" --steps 5 -steps 5
one "$train" "did you mean --checkpoint-every?" --checkpoint 5
one "$train" "did you mean --preset?" --prest fast
one "$train" "bad value 'abc' for --steps" --data d --out m --steps abc
one "$train" "bad value 'huge' for --preset" --preset huge
one "$train" "--seed needs a value" --data d --out m --seed
one "$train" "unknown option '--frobnicate';" --frobnicate
one "$train" "unexpected argument 'scene'" scene
one "$train" "--data and --out are required"
one "$train" "bad value '1' for --coarse-samples" --data d --out m \
  --coarse-samples 1
one "$train" "bad value '4097' for --fine-samples" --data d --out m \
  --fine-samples 4097
one "$train" "the fast preset places its own by marching" --data d --out m \
  --preset fast --fine-samples 0
one "$train" "--coarse-samples 2 leaves the fine samples nothing" \
  --data d --out m --coarse-samples 2
one "$render" "did you mean --width?" --widht 8
one "$render" "did you mean --frames?" --frame 8
one "$render" "did you mean --downscale?" --downsacle 2
one "$render" "bad value 'circle' for --path" --path circle
one "$render" "did you mean --video?" --vidoe orbit.mp4
one "$eval" "did you mean --skip?" --skipp 8
one "$eval" "did you mean --json?" --jsno
one "$eval" "bad value 'all' for --split" --split all
one "$scene" "did you mean --train?" --trian 4
one "$scene" "did you mean --layout?" --lay llff
one "$scene" "bad value 'x' for --width" --width x
one "$scene" "--capture needs one of" --capture indoor
one "$info" "unknown option '--verbose'" --verbose
if [ -n "$viewer" ]; then
  one "$viewer" "did you mean --screenshot?" --screenshoot a.png
  one "$viewer" "--downscale shrinks the images of --data" \
    --model "$work/m.nerf" --downscale 2
fi
one "$scene" "--val: an LLFF layout has no validation views" \
  --out "$work/llff" --capture forward --val 2
[ ! -e "$work/llff" ] || fail "nerf-scene wrote a scene it refused"

# An option that cannot apply is said to be ignored, not dropped silently:
# a resumed model keeps the learning-rate schedule and the samples it was
# saved with.
$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 1 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 2>"$work/train.log" ||
  { cat "$work/train.log"; exit 1; }
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 3 \
  --batch 64 --resume --lr 0.1 --coarse-samples 4 2>"$work/resume.log" ||
  { cat "$work/resume.log"; exit 1; }
grep -qF "nerf-train: --lr and --lr-final ignored" "$work/resume.log" ||
  { cat "$work/resume.log"; fail "--lr on --resume dropped silently"; }
grep -qF "nerf-train: --coarse-samples and --fine-samples ignored" \
  "$work/resume.log" ||
  { cat "$work/resume.log"; fail "--coarse-samples on --resume dropped"; }

# failed PROGRAM WORDS ARGS...: PROGRAM exits 1 with WORDS in its message,
# which must not call a missing or foreign file an input/output error.
failed() {
  prog=$1 words=$2
  shift 2
  name=$(basename "$prog")
  status=0
  $wrap "$prog" "$@" >"$work/out" 2>"$work/err" || status=$?
  [ "$status" -eq 1 ] || { cat "$work/err"; fail "$name $*: status $status"; }
  grep -qF -- "$words" "$work/err" ||
    { cat "$work/err"; fail "$name $*: no '$words'"; }
  ! grep -q "input/output" "$work/err" ||
    { cat "$work/err"; fail "$name $*: reads like a failing disk"; }
}
mkdir "$work/empty"
failed "$eval" "nerf-eval: no such file or folder: $work/nope.nerf" \
  --model "$work/nope.nerf" --data "$work/scene"
failed "$eval" "not a recognised file or folder: $work/scene: a folder" \
  --model "$work/scene" --data "$work/scene"
failed "$eval" "not a libnerf checkpoint" \
  --model "$work/scene/transforms_train.json" --data "$work/scene"
failed "$eval" "no such file or folder: $work/nowhere" \
  --model "$work/model.nerf" --data "$work/nowhere"
rm "$work/scene/transforms_val.json"
failed "$eval" "has no val split" \
  --model "$work/model.nerf" --data "$work/scene" --split val
failed "$train" "not a recognised file or folder: $work/empty" \
  --data "$work/empty" --out "$work/other.nerf"
failed "$train" "not a known dataset layout" \
  --data "$work/empty" --out "$work/other.nerf"
failed "$render" "no such file or folder: $work/path.json" \
  --model "$work/model.nerf" --poses "$work/path.json" --out "$work/frames"
rm -f "$work/model.nerf"

# Nothing was created on the way.
[ ! -e "$work/m.nerf" ] || fail "a model was written"
echo "ok"
