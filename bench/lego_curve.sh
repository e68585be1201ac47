#!/usr/bin/env bash
#
# Test PSNR against training wall time for the fast preset on a Blender
# scene: ./bench/lego_curve.sh [DATA [OUT]]
#
# Two ways to draw it:
#  - by budget (the default): each mark is its own run, nerf-train
#    --seconds (minutes x 60) from scratch, so each point is what a user
#    asking for that much time gets (the schedule fitted to it, saves
#    every 2 minutes inside the budget).  The training time is the sum of
#    the marks (68 minutes for the default).
#  - by steps (NERF_CURVE_STEPS set): one training run, stopped at each
#    mark with nerf-train --seconds and continued with --resume, which
#    trains on bit for bit as an unbroken run would, its learning rate
#    decaying tenfold over NERF_CURVE_STEPS; it saves only at the marks,
#    and saving is not training time.
# The model at each mark is evaluated with nerf-eval on the test split.
# Loading the images is not training time.
#
#   NERF_CURVE_MARKS  minutes (default "1 2 5 10 20 30")
#   NERF_CURVE_STEPS  draw by steps, the decay over this many (default
#                     unset: by budget)
#   NERF_CURVE_SKIP   nerf-eval --skip at the marks before the last: every
#                     K-th test view (default 8: 25 views of lego, about two
#                     minutes each)
#   NERF_CURVE_FINAL_SKIP  the same at the last mark (default 1: all 200
#                     views, the full protocol)
#   NERF_CURVE_ARGS   more nerf-train arguments (default none)
#   NERF_CURVE_BUILD  build folder (default build/release)
#
# Prints one line per mark: minutes, step, test PSNR, SSIM, eval seconds.

set -eu

cd "$(dirname "${BASH_SOURCE[0]}")/.."
# shellcheck source=scripts/deps.sh
. scripts/deps.sh

data=${1:-../shared/data/lego}
out=${2:-out/curve}
marks=${NERF_CURVE_MARKS:-1 2 5 10 20 30}
steps=${NERF_CURVE_STEPS:-}
skip=${NERF_CURVE_SKIP:-8}
final_skip=${NERF_CURVE_FINAL_SKIP:-1}
# shellcheck disable=SC2206 # extra arguments are meant to split
extra=(${NERF_CURVE_ARGS:-})
build=${NERF_CURVE_BUILD:-build/release}

if [ ! -f "$data/transforms_train.json" ]; then
  echo "lego_curve: $data has no transforms_train.json (see" \
       "../shared/data/README.md)" >&2
  exit 1
fi
nerf_configure "$build" "${NERF_RELEASE_OPTIONS[@]}" >/dev/null
meson compile -C "$build" nerf-train nerf-eval >/dev/null
mkdir -p "$out"
model=$out/fast.nerf
rm -f "$model"

done_s=0
last=${marks##* }
printf '%-8s %-7s %-9s %-7s %-6s %s\n' minutes step psnr ssim views eval_s
for m in $marks; do
  if [ -n "$steps" ]; then
    todo=$((m * 60 - done_s))
    how=(--steps "$steps" --seconds "$todo" --resume
         --checkpoint-every 1000000)
  else
    rm -f "$model"
    how=(--seconds "$((m * 60))")
  fi
  "$build/examples/nerf-train" --data "$data" --out "$model" --preset fast \
      "${how[@]}" ${extra[@]+"${extra[@]}"} >"$out/train-$m.log" 2>&1
  done_s=$((m * 60))
  cp "$model" "$out/fast-${m}min.nerf"
  k=$skip
  if [ "$m" = "$last" ]; then
    k=$final_skip
  fi
  "$build/examples/nerf-eval" --model "$model" --data "$data" \
      --skip "$k" --json >"$out/eval-$m.json" 2>"$out/eval-$m.log"
  step=$(sed -n 's/.*(step \([0-9]*\),.*/\1/p' "$out/train-$m.log" | tail -1)
  "${PYTHON:-/usr/bin/python3}" -c '
import json, sys
e = json.load(open(sys.argv[1]))
print("%-8s %-7s %-9.2f %-7.4f %-6d %.0f" % (sys.argv[2], sys.argv[3],
      e["psnr"], e["ssim"], e["views"], e["seconds"]))' \
      "$out/eval-$m.json" "$m" "${step:-?}"
done
