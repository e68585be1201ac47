#!/bin/sh
# Tests of nerf-viewer on a tiny model trained here for a few steps.
#
#   test-viewer.sh screenshot|window NERF-SCENE NERF-TRAIN NERF-VIEWER PNG-CHECK
#
# screenshot: render views headless (no display, SDL never started) and
#             check each PNG has the right size and more than one colour
#             (colour and depth: this young model's opacity is 1 all over).
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
