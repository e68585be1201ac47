#!/bin/sh
# Tests of nerf-viewer on a tiny model trained here for a few steps.
#
#   test-viewer.sh screenshot|window NERF-SCENE NERF-TRAIN NERF-VIEWER PNG-CHECK
#
# screenshot: render views headless (no display, SDL never started) and
#             check each PNG has the right size and more than one colour
#             (colour and depth: this young model's opacity is 1 all over),
#             and --march-steps on a fast model.
# window:     run the interactive viewer for a second under Xvfb and check
#             it exits 0 having drawn something; skipped (77) without
#             xvfb-run.
set -eu
mode=$1 scene=$2 train=$3 viewer=$4 check=$5

if [ "$mode" = window ] && ! command -v xvfb-run >/dev/null 2>&1; then
  echo "xvfb-run not found (Debian package xvfb): skipping"
  exit 77
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-viewer-test.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Ten steps are far from a good model but give a density field with
# structure, which is all these tests need.
"$scene" --out "$work/scene" --width 32 --height 32 --train 12 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
"$train" --data "$work/scene" --out "$work/model.nerf" --steps 10 \
  --batch 128 2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

case $mode in
screenshot)
  # Unset DISPLAY proves no window system is needed.
  env -u DISPLAY "$viewer" --model "$work/model.nerf" --width 48 \
    --height 40 --screenshot "$work/rgb.png"
  "$check" "$work/rgb.png" 48 40
  # With the data: the start view comes from its first camera, the height
  # from its aspect ratio.
  env -u DISPLAY "$viewer" --model "$work/model.nerf" --data "$work/scene" \
    --width 36 --view depth --screenshot "$work/depth.png"
  "$check" "$work/depth.png" 36 36
  # A screenshot replaces a file only with --overwrite, and the model
  # never: both refused with status 2, the files untouched.
  # refused WORDS FLAGS...: status 2 and WORDS on stderr.
  refused() {
    words=$1
    shift
    status=0
    env -u DISPLAY "$viewer" --model "$work/model.nerf" --width 8 "$@" \
      2>"$work/refused.log" || status=$?
    [ "$status" -eq 2 ] || { cat "$work/refused.log"; echo "$*: $status"; exit 1; }
    grep -qF -- "$words" "$work/refused.log" ||
      { cat "$work/refused.log"; echo "$*: message"; exit 1; }
  }
  cp "$work/model.nerf" "$work/model.copy"
  refused "rgb.png exists: --overwrite replaces it" --screenshot "$work/rgb.png"
  refused "is the same file as --model" --screenshot "$work/model.nerf" \
    --overwrite
  cmp -s "$work/model.nerf" "$work/model.copy" || { echo "model changed"; exit 1; }
  "$check" "$work/rgb.png" 48 40
  env -u DISPLAY "$viewer" --model "$work/model.nerf" --width 8 \
    --screenshot "$work/rgb.png" --overwrite
  "$check" "$work/rgb.png" 8 8
  # --march-steps: a fast model drawn in its recorded 1280 steps again is
  # the same picture, in 4096 another (a new model has density all over,
  # so the spacing shows); a bad value and a model that cannot march are
  # refused.
  "$train" --data "$work/scene" --out "$work/fast.nerf" --preset fast \
    --steps 2 --batch 64 --checkpoint-every 0 2>"$work/fast.log" ||
    { cat "$work/fast.log"; exit 1; }
  # shot NAME MODEL [FLAGS...]: MODEL's start view into NAME.png
  shot() {
    name=$1 model=$2
    shift 2
    env -u DISPLAY "$viewer" --model "$work/$model" --width 24 \
      --height 24 "$@" --screenshot "$work/$name.png"
  }
  shot march-as-recorded fast.nerf
  shot march-1280 fast.nerf --march-steps 1280
  shot march-4096 fast.nerf --march-steps 4096
  if ! cmp -s "$work/march-as-recorded.png" "$work/march-1280.png"; then
    echo "--march-steps 1280 changed the recorded march's picture"
    exit 1
  fi
  if cmp -s "$work/march-as-recorded.png" "$work/march-4096.png"; then
    echo "--march-steps 4096 drew the recorded march's picture"
    exit 1
  fi
  # refused MODEL FLAGS...: the viewer fails and says why
  refused() {
    if shot bad "$@" 2>"$work/bad.log"; then
      echo "nerf-viewer --model $*: accepted"
      exit 1
    fi
    if ! grep -Eq "bad value '0' for --march-steps|occupancy grid" \
         "$work/bad.log"; then
      cat "$work/bad.log"
      echo "nerf-viewer --model $*: no reason given"
      exit 1
    fi
  }
  refused fast.nerf --march-steps 0
  refused model.nerf --march-steps 2048
  ;;
window)
  status=0
  # SDL's software renderer keeps Mesa out: its driver threads, and its
  # allocations that LeakSanitizer reports once the driver is unloaded.
  xvfb-run -a -s "-screen 0 320x240x24" env SDL_VIDEODRIVER=x11 \
    SDL_RENDER_DRIVER=software SDL_FRAMEBUFFER_ACCELERATION=0 \
    "$viewer" --model "$work/model.nerf" --width 64 --height 48 \
    --quit-after 1 2>"$work/viewer.log" || status=$?
  cat "$work/viewer.log"
  if [ "$status" -ne 0 ]; then
    echo "nerf-viewer exited with status $status"
    exit 1
  fi
  if ! grep -Eq ' [1-9][0-9]* previews' "$work/viewer.log"; then
    echo "nerf-viewer did not report drawing a preview"
    exit 1
  fi
  ;;
*)
  echo "unknown mode '$mode'"
  exit 2
  ;;
esac
