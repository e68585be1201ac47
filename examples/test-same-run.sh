#!/bin/sh
# A C or Python caller who asks for a preset trains what nerf-train trains
# (docs/api-notes.md, "A run as nerf-train sets it up"): the C tutorial,
# the Python one when given, and nerf-train, each with the same preset,
# seed (0) and steps on the same scene, write the same checkpoint, byte
# for byte.  Any choice that one of them makes on its own (a learning
# rate, a batch, a crop, a background, a march, the products) shows here.
#
#   test-same-run.sh TUTORIAL NERF-TRAIN [PYTHON TUTORIAL.PY]
set -eu
tutorial=$1 train=$2
python=${3:-} tutorial_py=${4:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-same-run.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# Enough steps for the fast preset's occupancy grid to be refreshed and
# its schedule to move; the reference preset is left out for its time.
steps=20
for preset in tiny fast; do
  c=$work/c-$preset
  "$tutorial" "$c" $steps 1 $preset >"$work/c.log" 2>&1 ||
    { cat "$work/c.log"; fail "tutorial $preset"; }
  "$train" --data "$c/scene" --out "$work/train-$preset.nerf" \
    --preset $preset --steps $steps >"$work/train.log" 2>&1 ||
    { cat "$work/train.log"; fail "nerf-train $preset"; }
  cmp "$c/model.nerf" "$work/train-$preset.nerf" ||
    fail "$preset: the C tutorial's checkpoint differs from nerf-train's"
  echo "ok: $preset: the C tutorial and nerf-train agree"
  if [ -n "$python" ]; then
    p=$work/py-$preset
    "$python" "$tutorial_py" "$p" $steps 1 $preset >"$work/py.log" 2>&1 ||
      { cat "$work/py.log"; fail "tutorial.py $preset"; }
    cmp "$p/model.nerf" "$work/train-$preset.nerf" ||
      fail "$preset: the Python tutorial's checkpoint differs from nerf-train's"
    echo "ok: $preset: the Python tutorial and nerf-train agree"
  fi
done
if [ -z "$python" ]; then
  echo "note: the Python tutorial not run (no binding environment here)"
fi
