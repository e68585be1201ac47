#!/bin/sh
# shellcheck disable=SC2086 # $wrap is empty or a command to split
# nerf-train --matmul, for each of oneDNN's kinds (bf16, fp32-onednn): a
# model trained for a few steps, resumed (the checkpoint keeps its kind
# whatever --matmul says), evaluated where the kind runs and where it does
# not (oneDNN capped at AVX2: it loads as fp32, with a warning); then a bad
# value refused.  A kind not available at all is skipped; exit 77
# (skipped) when neither is.
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

# check KIND: 0 when it ran and passed, 1 when KIND is not available here.
check() {
  kind=$1 m="$work/$1.nerf"
  if ! $wrap "$train" --data "$work/scene" --out "$m" --steps 3 \
       --batch 64 --matmul "$kind" 2>"$work/train.log"; then
    if grep -q "products are not available" "$work/train.log"; then
      echo "skipped $kind: $(grep 'not available' "$work/train.log")"
      return 1
    fi
    cat "$work/train.log"
    fail "nerf-train --matmul $kind"
  fi

  # Taken on the fast preset too, but with a word that it is slower there.
  $wrap "$train" --data "$work/scene" --out "$work/fast.nerf" --overwrite \
    --preset fast --steps 2 --batch 64 --matmul "$kind" \
    2>"$work/fast.log" ||
    { cat "$work/fast.log"; fail "nerf-train --preset fast --matmul $kind"; }
  grep -q "$kind products through oneDNN: the fast preset trains faster" \
    "$work/fast.log" ||
    { cat "$work/fast.log"; fail "--preset fast --matmul $kind: no word"; }

  $wrap "$train" --data "$work/scene" --out "$m" --steps 4 --batch 64 \
    --matmul fp32 --resume 2>"$work/resume.log" ||
    { cat "$work/resume.log"; fail "nerf-train --resume ($kind)"; }
  grep -q "keeps the $kind products" "$work/resume.log" ||
    { cat "$work/resume.log"; fail "--resume did not say it keeps $kind"; }

  $wrap "$eval" --model "$m" --data "$work/scene" >"$work/kind.txt" \
    2>"$work/eval.log" || { cat "$work/eval.log"; fail "nerf-eval ($kind)"; }
  if grep -q "computes in fp32" "$work/eval.log"; then
    fail "nerf-eval fell back to fp32 where $kind runs"
  fi
  DNNL_MAX_CPU_ISA=AVX2 $wrap "$eval" --model "$m" --data "$work/scene" \
    >"$work/fp32.txt" 2>"$work/eval32.log" ||
    { cat "$work/eval32.log"; fail "nerf-eval, $kind capped"; }
  grep -q "computes in fp32" "$work/eval32.log" ||
    { cat "$work/eval32.log"; fail "no warning when $kind is not available"; }

  # The same weights: the two evaluations agree to rounding.  A difference
  # d between two renders changes the PSNR by at most 8.69 RMS(d)/RMS(e),
  # e the render's error against the images (RMS 0.4 for a model of four
  # steps): 0.1 dB takes an RMS(d) of 4.6e-3, more than an 8-bit level,
  # where bf16's rounding of operands moves colours by about 1e-3 and
  # fp32 orders of sums by about 1e-6, on any processor.
  pk=$(awk '/^mean/ { print $3 }' "$work/kind.txt")
  p32=$(awk '/^mean/ { print $3 }' "$work/fp32.txt")
  awk -v a="$pk" -v b="$p32" 'BEGIN { d = a - b; if (d < 0) d = -d;
    exit !(a != "" && d < 0.1) }' || fail "PSNR $kind $pk against fp32 $p32"
  echo "ok: $kind trained, resumed and evaluated (PSNR $pk; as fp32 $p32)"
  return 0
}

ran=0
for kind in bf16 fp32-onednn; do
  if check "$kind"; then
    ran=$((ran + 1))
  fi
done

if $wrap "$train" --data "$work/scene" --out "$work/x.nerf" --matmul fp16 \
     2>"$work/bad.log"; then
  fail "--matmul fp16 accepted"
fi
grep -q "bad value 'fp16' for --matmul" "$work/bad.log" ||
  { cat "$work/bad.log"; fail "--matmul fp16: no message"; }
if [ "$ran" -eq 0 ]; then
  echo "SKIP: neither bf16 nor fp32-onednn products are available here"
  exit 77
fi
