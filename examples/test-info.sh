#!/bin/sh
# shellcheck disable=SC2086 # $wrap is empty or a command to split
# nerf-info: build information without arguments; with a model, what it
# is and holds (text and --json), nerf-train's sample counts among it;
# --export writes a weights-only file that renders and evaluates but that
# nerf-train refuses to resume; a model trained on a forward-facing scene
# renders from a camera path alone, with the NDC settings it recorded.
#
#   test-info.sh NERF-SCENE NERF-TRAIN NERF-RENDER NERF-EVAL NERF-INFO PYTHON
set -eu
scene=$1 train=$2 render=$3 eval=$4 info=$5 python=$6
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-info.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# expect STATUS LOG PATTERN COMMAND...: the status, and PATTERN in stdout
# and stderr together.
expect() {
  want=$1 log=$2 pattern=$3
  shift 3
  status=0
  $wrap "$@" >"$work/$log" 2>&1 || status=$?
  [ "$status" -eq "$want" ] ||
    { cat "$work/$log"; fail "$*: status $status, expected $want"; }
  grep -q -- "$pattern" "$work/$log" ||
    { cat "$work/$log"; fail "$*: no '$pattern'"; }
}

# Without arguments: the build, as before.
expect 0 build.log "libnerf" "$info"
# Usage errors: one line naming the program, not its build path.
expect 2 bad.log "^nerf-info: unknown option '--bogus'.*nerf-info --help" \
  "$info" --bogus
[ "$(wc -l <"$work/bad.log")" -eq 1 ] || { cat "$work/bad.log"; fail "bad.log"; }
expect 2 two.log "one MODEL at a time" "$info" a.nerf b.nerf
expect 0 help.log "nerf-info lego.nerf --export" "$info" --help
expect 1 missing.log "$work/nope.nerf" "$info" "$work/nope.nerf"

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 2 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: the model records
# them (checked below), and training and rendering pay for each, most of
# all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

# field LOG KEY: the value of a text line "KEY  value".
field() {
  sed -n "s/^$2  *//p" "$work/$1" | sed 's/ (.* MB)$//'
}
expect 0 full.txt "^kind *checkpoint" "$info" "$work/model.nerf"
[ "$(field full.txt preset)" = "tiny" ] || fail "preset: $(field full.txt preset)"
[ "$(field full.txt step)" = "2" ] || fail "step: $(field full.txt step)"
# nerf-train's default products: oneDNN's fp32 where they run (it says so).
matmul=fp32
if grep -q "through oneDNN" "$work/train.log"; then
  matmul=fp32-onednn
fi
[ "$(field full.txt matmul)" = "$matmul" ] ||
  fail "matmul: $(field full.txt matmul), expected $matmul"
[ "$(field full.txt space)" = "box" ] || fail "space"
[ "$(field full.txt holds)" = "weights, optimiser moments, render settings, data record, batch record" ] ||
  fail "holds: $(field full.txt holds)"
[ "$(field full.txt batch)" = "rays 64, samples 0" ] ||
  fail "batch: $(field full.txt batch)"
field full.txt data | grep -q "^4 images of 16x16 (blender, mean colour" ||
  fail "data: $(field full.txt data)"
field full.txt encoding | grep -q "positions frequency, frequencies 10" ||
  fail "encoding: $(field full.txt encoding)"
field full.txt render | grep -q "recorded in training, n_coarse 8, n_fine 16, near 2, far 6, ndc no, background white" ||
  fail "render: $(field full.txt render)"

# The export: smaller, weights only, and both sizes said.
expect 0 export.txt "^kind *weights-only" \
  "$info" "$work/model.nerf" --export "$work/weights.nerf"
full=$(field full.txt bytes) part=$(field export.txt bytes)
echo "checkpoint $full bytes, weights-only export $part bytes"
[ "$full" = "$(wc -c <"$work/model.nerf")" ] || fail "checkpoint size"
[ "$part" = "$(wc -c <"$work/weights.nerf")" ] || fail "export size"
[ $((2 * part)) -lt "$full" ] || fail "the export is not smaller"
[ "$(field export.txt holds)" = "weights, render settings, data record, batch record" ] ||
  fail "export holds: $(field export.txt holds)"
[ "$(field export.txt parameters)" = "$(field full.txt parameters)" ] ||
  fail "parameters"

# --json says the same, as JSON.
$wrap "$info" "$work/weights.nerf" --json >"$work/info.json"
"$python" - "$work/info.json" "$(field full.txt parameters)" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
assert d["kind"] == "weights-only", d
assert d["preset"] == "tiny" and d["step"] == 2, d
assert d["parameters"] == int(sys.argv[2]), d
assert d["encoding"]["positions"] == "frequency", d
assert d["render"]["background"] == "white", d
assert d["render"]["n_coarse"] == 8 and d["render"]["n_fine"] == 16, d
assert d["batch"] == {"rays": 64, "samples": 0}, d
PY

# The export renders and evaluates; training does not resume from it.
$wrap "$render" --model "$work/weights.nerf" --data "$work/scene" \
  --split test --out "$work/frames" 2>"$work/render.log" ||
  { cat "$work/render.log"; fail "render the export"; }
[ -f "$work/frames/r_001.png" ] || ls "$work/frames"
$wrap "$eval" --model "$work/weights.nerf" --data "$work/scene" \
  >"$work/eval.log" 2>&1 || { cat "$work/eval.log"; fail "eval the export"; }
expect 1 resume.log "weights-only export.*resume from the full checkpoint" \
  "$train" --data "$work/scene" --out "$work/weights.nerf" --steps 4 \
  --batch 64 --resume

# A forward-facing scene: the model records NDC, its frustum and black,
# and a camera path alone renders it with them.  Trained on the coarse
# network alone (--fine-samples 0), which it records and renders with.
$wrap "$scene" --out "$work/ff" --capture forward --width 16 --height 12 \
  --train 4 --test 1 2>"$work/ff-scene.log" ||
  { cat "$work/ff-scene.log"; exit 1; }
$wrap "$train" --data "$work/ff" --out "$work/ff.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 0 \
  2>"$work/ff-train.log" || { cat "$work/ff-train.log"; exit 1; }
expect 0 ff.txt "^render .*ndc yes, ndc_focal" "$info" "$work/ff.nerf"
field ff.txt render | grep -q "n_coarse 8, n_fine 0, near 0, far 1, .*background black" ||
  fail "ff render: $(field ff.txt render)"
$wrap "$render" --model "$work/ff.nerf" --data "$work/ff" \
  --out "$work/ff-frames" --path spiral --frames 1 --width 8 --height 6 \
  2>"$work/ff-render.log" ||
  { cat "$work/ff-render.log"; fail "render the forward-facing model"; }
set -- "$work"/ff-frames/*.png
[ -s "$1" ] || fail "no frame of the forward-facing model"
echo "ok"
