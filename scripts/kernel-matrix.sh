#!/usr/bin/env bash
#
# The test suites under every kernel this machine can run (docs/dispatch.md):
#
#   scripts/kernel-matrix.sh [BUILD] [-- MESON-TEST-ARGS...]
#
# BUILD (default build/release) must be built already.  Each row runs
# `meson test` in it with one choice of kernels set through the environment:
#   - libnerf's own: NERF_ISA (AVX-512, AVX2 and baseline clones and small
#     products), NERF_FUSED (fused or per-layer networks; the portable
#     fused kernels), NERF_FP32_PRODUCTS (oneDNN's fp32 products instead of
#     the CBLAS);
#   - OpenBLAS's: OPENBLAS_CORETYPE, once for each x86-64 kernel family the
#     installed OpenBLAS has and this processor runs.  A family runs here
#     when test_gemm (every product shape the library uses) passes under it;
#     one that dies of an illegal instruction is listed as not runnable.
# It prints a table, row by row, of what each row chose (nerf_build_info()'s
# kernels, OpenBLAS's core) and its counts, then "N passed, N failed" over
# all rows.  Exit status 1 if any test failed.  NERF_MATRIX_ROWS="a b"
# runs only the rows of those labels.  Takes about as many times the
# release suites' time as there are rows (an hour on the 2-core machine).

set -u
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build=build/release
if [ $# -gt 0 ] && [ "$1" != "--" ]; then
  build=$1
  shift
fi
[ "${1:-}" = "--" ] && shift
test_args=("$@")

info=$build/examples/nerf-info
gemm=$build/tests/model/test_gemm
for f in "$info" "$gemm"; do
  [ -x "$f" ] || { echo "kernel-matrix: $f not built (meson compile -C $build)" >&2; exit 2; }
done

# label|environment (space-separated assignments)
rows=(
  "default|"
  "isa-avx2|NERF_ISA=avx2"
  "isa-baseline|NERF_ISA=baseline"
  "baseline-fused|NERF_ISA=baseline NERF_FUSED=1"
  "per-layer|NERF_FUSED=0"
  "avx2-per-layer|NERF_ISA=avx2 NERF_FUSED=0"
  "onednn-fp32|NERF_FP32_PRODUCTS=onednn"
)

# OpenBLAS's kernel families: the names its DYNAMIC_ARCH build answers to
# with a core of their own (aliases of one family are left out).
families=()
for name in Prescott Atom Core2 Penryn Dunnington Nehalem Opteron \
            Opteron_SSE3 Barcelona Nano Sandybridge Bobcat Haswell \
            Bulldozer Piledriver Steamroller Excavator SkylakeX Zen \
            CooperLake SapphireRapids; do
  core=$(OPENBLAS_VERBOSE=2 OPENBLAS_CORETYPE=$name "$info" 2>&1 >/dev/null |
         sed -n 's/^Core: //p')
  [ -n "$core" ] || continue
  case " ${families[*]-} " in *" $core "*) continue ;; esac
  families+=("$core")
done
unrunnable=()
for core in "${families[@]}"; do
  if OPENBLAS_CORETYPE=$core "$gemm" >/dev/null 2>&1; then
    rows+=("openblas-$core|OPENBLAS_CORETYPE=$core")
  else
    status=$?
    # 132: SIGILL through the shell; the test's own failures are 1.
    if [ "$status" -ge 128 ]; then
      unrunnable+=("$core (signal $((status - 128)))")
    else
      rows+=("openblas-$core|OPENBLAS_CORETYPE=$core")
    fi
  fi
done

total_pass=0
total_fail=0
table=()
for row in "${rows[@]}"; do
  label=${row%%|*}
  vars=${row#*|}
  if [ -n "${NERF_MATRIX_ROWS:-}" ] &&
     [[ " $NERF_MATRIX_ROWS " != *" $label "* ]]; then
    continue
  fi
  # shellcheck disable=SC2206 # the assignments are meant to split
  assignments=($vars)
  chosen=$(env "${assignments[@]}" OPENBLAS_VERBOSE=2 "$info" 2>&1)
  core=$(printf '%s\n' "$chosen" | sed -n 's/^Core: //p')
  kernels=$(printf '%s\n' "$chosen" | sed -n 's/.*; kernels //p')
  echo "== $label: $vars (kernels $kernels; OpenBLAS core ${core:-?})"
  log=$build/meson-logs/testlog-matrix-$label.json
  rm -f "$log"
  env "${assignments[@]}" meson test -C "$build" --no-rebuild \
    --print-errorlogs --logbase "testlog-matrix-$label" \
    ${test_args[@]+"${test_args[@]}"} >"$build/meson-logs/matrix-$label.out" 2>&1
  counts=$(/usr/bin/python3 - "$log" <<'PY'
import json, sys
ok = bad = skip = 0
failed = []
try:
    lines = open(sys.argv[1], encoding="utf-8").read().splitlines()
except OSError:
    lines = []
for line in lines:
    if not line.strip():
        continue
    j = json.loads(line)
    r = j.get("result")
    if r in ("OK", "EXPECTEDFAIL"):
        ok += 1
    elif r == "SKIP":
        skip += 1
    else:
        bad += 1
        failed.append(j.get("name", "?"))
print(ok, bad, skip, ",".join(failed) or "-")
PY
  )
  read -r ok bad skip names <<<"$counts"
  if [ $((ok + bad + skip)) -eq 0 ]; then
    bad=1
    names="(no tests ran: see $build/meson-logs/matrix-$label.out)"
  fi
  total_pass=$((total_pass + ok))
  total_fail=$((total_fail + bad))
  table+=("| $label | ${vars:-(none)} | $kernels | ${core:-?} | $ok | $bad | $skip | $names |")
  echo "   $ok passed, $bad failed, $skip skipped${bad:+ }$([ "$bad" -gt 0 ] && echo "($names)")"
done

echo
echo "Processor: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)"
[ ${#unrunnable[@]} -eq 0 ] ||
  echo "OpenBLAS families this processor cannot run: ${unrunnable[*]}"
echo
echo "| row | environment | libnerf kernels | OpenBLAS core | passed | failed | skipped | failing |"
echo "|---|---|---|---|---:|---:|---:|---|"
printf '%s\n' "${table[@]}"
echo
echo "$total_pass passed, $total_fail failed"
[ "$total_fail" -eq 0 ]
