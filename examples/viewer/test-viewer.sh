#!/bin/sh
# Tests of nerf-viewer on a tiny model trained here for a few steps.
#
#   test-viewer.sh screenshot|window|fly|fly-bake NERF-SCENE NERF-TRAIN NERF-VIEWER PNG-CHECK
#
# screenshot: render views headless (no display, SDL never started) and
#             check each PNG has the right size and more than one colour
#             (colour and depth: this young model's opacity is 1 all over),
#             and --march-steps on a fast model.
# window:     run the interactive viewer for a second under Xvfb and check
#             it exits 0 having drawn something; skipped (77) without
#             xvfb-run.
# fly:        fly --fly's path under Xvfb and check that its report is
#             whole and agrees with itself: a line a frame, at most 60
#             of them scored, the summary's median, 95th percentile and
#             PSNR those of the lines, the frames spanning the path;
#             skipped (77) without xvfb-run.
# fly-bake:   the same with the moving views drawn from a bake, of a fast
#             model trained until its grid is carved (300 steps): the
#             report agrees with itself and some frames are drawn at the
#             window's full size, which only a bake's previews are;
#             skipped (77) without xvfb-run, and in the sanitizers' run
#             (NERF_TEST_QUICK), where the training takes minutes.
set -eu
mode=$1 scene=$2 train=$3 viewer=$4 check=$5

if [ "$mode" != screenshot ] && ! command -v xvfb-run >/dev/null 2>&1; then
  echo "xvfb-run not found (Debian package xvfb): skipping"
  exit 77
fi

# in_window COMMAND...: COMMAND under Xvfb.  SDL's software renderer keeps
# Mesa out: its driver threads, and its allocations that LeakSanitizer
# reports once the driver is unloaded.
in_window() {
  xvfb-run -a -s "-screen 0 320x240x24" env SDL_VIDEODRIVER=x11 \
    SDL_RENDER_DRIVER=software SDL_FRAMEBUFFER_ACCELERATION=0 "$@"
}

if [ "$mode" = fly-bake ] && [ -n "${NERF_TEST_QUICK:-}" ]; then
  echo "NERF_TEST_QUICK: skipping (the training takes minutes here)"
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

# check_fly_report FILE SECONDS: --fly's report in FILE, of a path of
# SECONDS, is whole and agrees with itself.
check_fly_report() {
  report=$1 seconds_flown=$2
  # The frames' lines: "frame K  MS ms  WxH  psnr P dB", P "-" for a
  # frame left unscored.
  grep '^frame ' "$report" | awk '{ print $3, $7 }' >"$work/lines"
  # The nearest-rank percentile P of column C of the lines (unscored
  # frames left out).
  ranked() {
    cut -d' ' -f"$2" "$work/lines" | grep -v '^-$' | sort -g >"$work/ranked"
    n=$(wc -l <"$work/ranked")
    awk -v p="$1" -v n="$n" 'BEGIN { k = int(p * n / 100); if (k < p * n / 100) k++; if (k < 1) k = 1 }
                             NR == k { print }' "$work/ranked"
  }
  # summary WORDS: the number after WORDS in the summary
  summary() {
    # (a PSNR of identical images prints as inf)
    sed -n "s/^fly: .*$1 \([0-9.inf]*\).*/\1/p" "$report" | head -n 1
  }
  frames=$(sed -n 's/^fly: \([0-9]*\) frames shown.*/\1/p' "$report")
  lines=$(wc -l <"$work/lines")
  check() {
    if [ "$2" != "$3" ]; then
      echo "$1: the summary says '$2', the frames' lines give '$3'"
      exit 1
    fi
  }
  [ -n "$frames" ] && [ "$frames" -ge 1 ] ||
    { echo "no summary of the frames shown"; exit 1; }
  check "frames" "$frames" "$lines"
  # At most 60 frames are scored, the summary says how many.
  scored=$(awk '$2 != "-"' "$work/lines" | wc -l)
  want=$((lines < 60 ? lines : 60))
  check "frames scored" "$(sed -n 's/^fly: .*(\([0-9]*\) of [0-9]*, evenly.*/\1/p' "$report")" "$scored"
  check "frames scored of $lines" "$want" "$scored"
  check "median frame time" "$(summary 'frame time median')" "$(ranked 50 1)"
  check "95th percentile" "$(summary '95th percentile')" "$(ranked 95 1)"
  check "median PSNR" "$(summary 'median PSNR')" "$(ranked 50 2)"
  # Each frame's time runs from the one before it was shown, the first's
  # from the path's start, and the last frame is drawn where the path
  # stopped: together they span the path (less the lines' rounding).
  awk -v s="$seconds_flown" -v n="$lines" '{ t += $1 }
    END { if (t < 1000 * s - 0.05 * n) { print "the frames span " t \
          " ms of a " s " s path"; exit 1 } }' "$work/lines"
  full=$(summary 'full quality')
  awk -v f="$full" 'BEGIN { exit !(f > 0) }' ||
    { echo "no time to full quality after the path: '$full'"; exit 1; }
}

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
  in_window "$viewer" --model "$work/model.nerf" --width 64 --height 48 \
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
fly)
  # --fly needs a window: with --screenshot it is refused.
  status=0
  env -u DISPLAY "$viewer" --model "$work/model.nerf" --width 8 --fly 1 \
    --screenshot "$work/fly.png" 2>"$work/refused.log" || status=$?
  if [ "$status" -ne 2 ] || ! grep -q -- "--fly flies in a window" \
       "$work/refused.log"; then
    cat "$work/refused.log"
    echo "--fly with --screenshot: status $status"
    exit 1
  fi
  seconds=1.5
  status=0
  in_window "$viewer" --model "$work/model.nerf" --width 64 --height 48 \
    --fly $seconds >"$work/fly.out" 2>"$work/viewer.log" || status=$?
  cat "$work/viewer.log" "$work/fly.out"
  if [ "$status" -ne 0 ]; then
    echo "nerf-viewer --fly exited with status $status"
    exit 1
  fi
  check_fly_report "$work/fly.out" $seconds
  # A marching model's previews march coarser, in a renderer of their
  # own: the path flies there too.  --preview-march is for a window.
  "$train" --data "$work/scene" --out "$work/fast.nerf" --preset fast \
    --steps 2 --batch 64 --checkpoint-every 0 2>"$work/fast.log" ||
    { cat "$work/fast.log"; exit 1; }
  status=0
  in_window "$viewer" --model "$work/fast.nerf" --width 16 --height 12 \
    --preview-march 64 --fly 0.3 >"$work/fly-fast.out" \
    2>"$work/viewer.log" || status=$?
  if [ "$status" -ne 0 ] || ! grep -q '^fly: full quality' "$work/fly-fast.out"; then
    cat "$work/viewer.log" "$work/fly-fast.out"
    echo "nerf-viewer --fly with a fast model: status $status"
    exit 1
  fi
  status=0
  env -u DISPLAY "$viewer" --model "$work/fast.nerf" --width 8 \
    --preview-march 64 --screenshot "$work/fly.png" 2>"$work/refused.log" ||
    status=$?
  if [ "$status" -ne 2 ] || ! grep -q -- "--preview-march is for a window" \
       "$work/refused.log"; then
    cat "$work/refused.log"
    echo "--preview-march with --screenshot: status $status"
    exit 1
  fi
  ;;
fly-bake)
  "$train" --data "$work/scene" --out "$work/fast.nerf" --preset fast \
    --steps 300 --batch 128 --checkpoint-every 0 2>"$work/fast.log" ||
    { cat "$work/fast.log"; exit 1; }
  seconds=1.5
  status=0
  in_window "$viewer" --model "$work/fast.nerf" --width 64 --height 48 \
    --bake 1 --fly $seconds >"$work/fly.out" 2>"$work/viewer.log" ||
    status=$?
  cat "$work/viewer.log" "$work/fly.out"
  if [ "$status" -ne 0 ]; then
    echo "nerf-viewer --bake 1 --fly exited with status $status"
    exit 1
  fi
  grep -q '^nerf-viewer: baking: done' "$work/viewer.log" ||
    { echo "nerf-viewer did not say it baked"; exit 1; }
  check_fly_report "$work/fly.out" $seconds
  # Previews from the networks are a quarter of the window's side at
  # most; a bake's take the window's whole size when they are quick.
  grep -q '^frame .*  64x48 ' "$work/fly.out" ||
    { echo "no frame drawn at the window's size"; exit 1; }
  ;;
*)
  echo "unknown mode '$mode'"
  exit 2
  ;;
esac
