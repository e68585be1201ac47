#!/usr/bin/env bash
#
# Test PSNR against training wall time for the fast preset on a Blender
# scene: ./bench/lego_curve.sh [DATA [OUT]]
#
# One training run, stopped at each mark (minutes of training time) with
# nerf-train --seconds and continued with --resume, which trains on bit for
# bit as an unbroken run would; the snapshot at each mark is evaluated with
# nerf-eval on the test split.  Loading the images and saving the model are
# not training time and are left out of the marks.
#
#   NERF_CURVE_MARKS  minutes (default "1 2 5 10 20 30")
#   NERF_CURVE_STEPS  --steps: the learning rate decays tenfold over them
#                     (default 10000, about what 30 minutes reach here)
#   NERF_CURVE_SKIP   nerf-eval --skip: every K-th test view (default 1,
#                     all 200 views of lego)
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
steps=${NERF_CURVE_STEPS:-10000}
skip=${NERF_CURVE_SKIP:-1}
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
printf '%-8s %-7s %-9s %-7s %s\n' minutes step psnr ssim eval_s
for m in $marks; do
  todo=$((m * 60 - done_s))
  "$build/examples/nerf-train" --data "$data" --out "$model" --preset fast \
      --steps "$steps" --seconds "$todo" --checkpoint-every 1000000 \
      --resume >"$out/train-$m.log" 2>&1
  done_s=$((m * 60))
  cp "$model" "$out/fast-${m}min.nerf"
  "$build/examples/nerf-eval" --model "$model" --data "$data" \
      --skip "$skip" --json >"$out/eval-$m.json" 2>"$out/eval-$m.log"
  step=$(sed -n 's/.*(step \([0-9]*\),.*/\1/p' "$out/train-$m.log" | tail -1)
  "${PYTHON:-/usr/bin/python3}" -c '
import json, sys
e = json.load(open(sys.argv[1]))
print("%-8s %-7s %-9.2f %-7.4f %.0f" % (sys.argv[2], sys.argv[3], e["psnr"],
      e["ssim"], e["seconds"]))' "$out/eval-$m.json" "$m" "${step:-?}"
done
