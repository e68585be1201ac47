#!/bin/sh
# Every program's --help teaches: it exits 0 on stdout alone, explains
# each option it has, states the default of each option that has one, and
# ends with real example commands.
#
#   test-help.sh NERF-SCENE NERF-TRAIN NERF-RENDER NERF-EVAL NERF-INFO
#                [NERF-VIEWER [NERF-FRAMES]]
# (the optional programs "" when not built)
set -eu
scene=$1 train=$2 render=$3 eval=$4 info=$5 viewer=${6:-} frames=${7:-}
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-help.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# entry OPTION: the help's paragraph for OPTION, from the line that starts
# with it to the next option or unindented line.
entry() {
  awk -v opt="$1" '
    /^  -/ { on = 0 }
    /^[^ ]/ { on = 0 }
    index($0, "  " opt " ") == 1 || $0 == "  " opt { on = 1 }
    on { print }' "$work/help"
}

# help PROGRAM [OPTION...]: PROGRAM --help is well-formed, and each
# OPTION has a paragraph that states its default.
help() {
  prog=$1
  shift
  name=$(basename "$prog")
  status=0
  $wrap "$prog" --help >"$work/help" 2>"$work/err" || status=$?
  [ "$status" -eq 0 ] || fail "$name --help: status $status"
  [ ! -s "$work/err" ] || { cat "$work/err"; fail "$name --help: stderr"; }
  grep -q "^usage: $name" "$work/help" || fail "$name --help: no usage line"
  # Two or three real commands after "Examples:", each naming a program.
  n=$(sed -n '/^Examples:$/,$p' "$work/help" | grep -c "^  nerf-" || true)
  [ "$n" -ge 1 ] || { cat "$work/help"; fail "$name --help: no Examples"; }
  grep -q "^  --help" "$work/help" || fail "$name --help: --help unexplained"
  for opt in "$@"; do
    entry "$opt" >"$work/entry"
    [ -s "$work/entry" ] || { cat "$work/help"; fail "$name: no $opt"; }
    grep -qi "default" "$work/entry" ||
      { cat "$work/entry"; fail "$name $opt: no default stated"; }
  done
}

help "$train" --preset --steps --seconds --downscale --batch --seed --lr \
  --lr-final --checkpoint-every --resume --batch-samples --random-background \
  --matmul --space --coarse-samples --fine-samples --render-march-steps
grep -q "^  --data DIR" "$work/help" || fail "nerf-train: --data unexplained"
grep -q "^  --out MODEL" "$work/help" || fail "nerf-train: --out unexplained"
help "$render" --split --downscale --frames --focal --fov --width --height \
  --depth --near --video --fps --march-steps --skip-existing --overwrite
for opt in --model --out --data "--path orbit" "--path spiral" --poses; do
  [ -n "$(entry "$opt")" ] || fail "nerf-render: $opt unexplained"
done
# How a grey level of depth_NNN.png becomes a depth.
entry --depth | grep -q "255" || fail "nerf-render --depth: no encoding"
help "$eval" --split --downscale --skip --json --march-steps
entry --skip | grep -q "0, K" || fail "nerf-eval --skip: numbering unsaid"
help "$scene" --width --height --train --val --test --threads \
  "--capture object" "--layout blender" --format --jpeg --distortion \
  --texture --overwrite
help "$info" --overwrite
if [ -n "$viewer" ]; then
  help "$viewer" --data --downscale "--width W," --view --march-steps \
    --screenshot --quit-after --overwrite
fi
if [ -n "$frames" ]; then
  help "$frames" --frames --quality --list --overwrite
  for opt in "--video FILE" "--out DIR"; do
    [ -n "$(entry "$opt")" ] || fail "nerf-frames: $opt unexplained"
  done
fi
echo "ok"
