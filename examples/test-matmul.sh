#!/bin/sh
# shellcheck disable=SC2086 # $wrap is empty or a command to split
# nerf-train --matmul: a bf16 model trained for a few steps, resumed (the
# checkpoint keeps bf16 whatever --matmul says), evaluated where bf16 runs
# and where it does not (oneDNN capped below AVX512-BF16: it loads as fp32,
# with a warning), and a bad value refused.  Exit 77 (skipped) where bf16
# is not available at all.
#
#   test-matmul.sh NERF-SCENE NERF-TRAIN NERF-EVAL
set -eu
scene=$1 train=$2 eval=$3
# In a cross build meson names the cross file's exe_wrapper (qemu-user,
# say) that runs the programs; natively it is unset and they run as is.
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-matmul.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 2 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }

if ! $wrap "$train" --data "$work/scene" --out "$work/m.nerf" --steps 3 \
     --batch 64 --matmul bf16 2>"$work/train.log"; then
  if grep -q "bf16 products are not available" "$work/train.log"; then
    echo "SKIP: $(grep 'not available' "$work/train.log")"
    exit 77
  fi
  cat "$work/train.log"
  fail "nerf-train --matmul bf16"
fi

$wrap "$train" --data "$work/scene" --out "$work/m.nerf" --steps 4 --batch 64 \
  --matmul fp32 --resume 2>"$work/resume.log" ||
  { cat "$work/resume.log"; fail "nerf-train --resume"; }
grep -q "keeps the bf16 products" "$work/resume.log" ||
  { cat "$work/resume.log"; fail "--resume did not say it keeps bf16"; }

$wrap "$eval" --model "$work/m.nerf" --data "$work/scene" >"$work/bf16.txt" \
  2>"$work/eval.log" || { cat "$work/eval.log"; fail "nerf-eval"; }
if grep -q "computes in fp32" "$work/eval.log"; then
  fail "nerf-eval fell back to fp32 where bf16 runs"
fi
DNNL_MAX_CPU_ISA=AVX2 $wrap "$eval" --model "$work/m.nerf" --data "$work/scene" \
  >"$work/fp32.txt" 2>"$work/eval32.log" ||
  { cat "$work/eval32.log"; fail "nerf-eval, bf16 capped"; }
grep -q "computes in fp32" "$work/eval32.log" ||
  { cat "$work/eval32.log"; fail "no warning when bf16 is not available"; }

# The same weights: the two evaluations agree to rounding.
p16=$(awk '/^mean/ { print $3 }' "$work/bf16.txt")
p32=$(awk '/^mean/ { print $3 }' "$work/fp32.txt")
awk -v a="$p16" -v b="$p32" 'BEGIN { d = a - b; if (d < 0) d = -d;
  exit !(a != "" && d < 0.1) }' || fail "PSNR bf16 $p16 against fp32 $p32"

if $wrap "$train" --data "$work/scene" --out "$work/x.nerf" --matmul fp16 \
     2>"$work/bad.log"; then
  fail "--matmul fp16 accepted"
fi
grep -q "bad value 'fp16' for --matmul" "$work/bad.log" ||
  { cat "$work/bad.log"; fail "--matmul fp16: no message"; }
echo "ok: bf16 trained, resumed and evaluated (PSNR $p16; as fp32 $p32)"
