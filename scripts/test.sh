#!/usr/bin/env bash
#
# libnerf's test command: ./scripts/test.sh [meson test arguments...]
#
# Installs missing Debian packages (as root; otherwise prints the apt-get
# line), then builds and tests, each build with --werror:
#   build/release   gcc, the test suites;
#   build/clang     the same with clang;
#   build/sanitize  gcc with AddressSanitizer + UndefinedBehaviorSanitizer;
#   build/fuzz      clang + libFuzzer: each fuzz target replays its corpus,
#                   then fuzzes for a few seconds (NERF_TEST_FUZZ=0: not);
#   build/aarch64   the abi, model and render suites cross-built for arm64
#                   and run under qemu-user (scripts/cross-aarch64.sh;
#                   NERF_TEST_CROSS=0: not).
# Extra arguments go to the `meson test` runs of the suites, for example
# `./scripts/test.sh --suite abi`.
#
# The last line of output is always "N passed, N failed, N skipped", summed
# over all runs; the exit status is non-zero if a build or a test failed.
# .ci/run relies on both.

set -eu

cd "$(dirname "${BASH_SOURCE[0]}")/.."
# shellcheck source=scripts/deps.sh
. scripts/deps.sh

passed=0
failed=0
skipped=0

summary() {
  echo "$passed passed, $failed failed, $skipped skipped"
}

# count_results LOG: add the results in meson's testlog.json to the totals.
# Each line of the log is one JSON object with a "result" field.
count_results() {
  local log=$1 counts
  if [ ! -s "$log" ]; then
    return 0
  fi
  # Debian's own interpreter: the python3 first on PATH may be another one.
  if [ -x /usr/bin/python3 ]; then
    counts=$(/usr/bin/python3 - "$log" <<'PY'
import json, sys
ok = bad = skip = 0
with open(sys.argv[1], encoding="utf-8") as f:
    for line in f:
        if not line.strip():
            continue
        result = json.loads(line).get("result")
        if result in ("OK", "EXPECTEDFAIL"):
            ok += 1
        elif result == "SKIP":
            skip += 1
        else:
            bad += 1
print(ok, bad, skip)
PY
    ) || counts=""
  fi
  if [ -z "${counts:-}" ]; then
    # Quotes inside JSON strings are escaped, so a bare "result": "X" can
    # only be the field itself.
    counts=$(grep -o '"result": *"[A-Z]*"' "$log" | awk '
      /"(OK|EXPECTEDFAIL)"$/ { ok++; next }
      /"SKIP"$/              { skip++; next }
                             { bad++ }
      END { print ok + 0, bad + 0, skip + 0 }')
  fi
  local ok bad skip
  read -r ok bad skip <<<"$counts"
  passed=$((passed + ok))
  failed=$((failed + bad))
  skipped=$((skipped + skip))
}

# run_suite NAME DIR -- SETUP-OPTIONS... -- ENV-ASSIGNMENTS...
# Configure, build and test one build directory.  Never exits: failures are
# counted so that the summary line still prints.
run_suite() {
  local name=$1 dir=$2
  shift 3
  local setup=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do
    setup+=("$1")
    shift
  done
  shift
  local envs=("$@")   # may be empty

  echo "== $name: configure $dir"
  if ! nerf_configure "$dir" "${setup[@]}"; then
    echo "== $name: meson setup failed (see $dir/meson-logs/meson-log.txt)"
    failed=$((failed + 1))
    return 0
  fi
  echo "== $name: build"
  if ! meson compile -C "$dir"; then
    echo "== $name: build failed"
    failed=$((failed + 1))
    return 0
  fi
  echo "== $name: test"
  local log="$dir/meson-logs/testlog.json" rc=0 before=$failed
  rm -f "$log"
  env ${envs[@]+"${envs[@]}"} meson test -C "$dir" --print-errorlogs \
    ${test_args[@]+"${test_args[@]}"} || rc=$?
  count_results "$log"
  if [ "$rc" -ne 0 ] && [ "$failed" -eq "$before" ]; then
    # meson test itself failed (bad argument, rebuild error, ...) without
    # recording a failing test; count it so the run cannot look green.
    echo "== $name: meson test exited with status $rc"
    failed=$((failed + 1))
  fi
  return 0
}

user_args=("$@")
test_args=("$@")

if ! nerf_ensure_packages; then
  failed=1
  summary
  exit 1
fi

nerf_offer_optional_packages

run_suite release build/release -- "${NERF_RELEASE_OPTIONS[@]}" --

# The same suites built by clang: macOS, FreeBSD and Android toolchains
# are clang, and it warns about other things than gcc does.
run_suite clang build/clang -- --native-file scripts/native/clang.ini \
  "${NERF_RELEASE_OPTIONS[@]}" --

# Sanitized code runs slower, hence the longer timeouts.  Leak checking is on
# so a missing free fails the test that leaked.  NERF_TEST_QUICK asks the
# tests that compare what several trainings reach (masks, appearance codes)
# for their code paths in a few steps: their figures, minutes of training
# here, are checked by the release and clang runs.
test_args=(--timeout-multiplier 3 ${test_args[@]+"${test_args[@]}"})
run_suite sanitize build/sanitize -- \
  -Db_sanitize=address,undefined -Db_lundef=false \
  -Dbuildtype=debugoptimized --werror -- \
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 NERF_TEST_QUICK=1

# The fuzz targets (clang, libFuzzer; tests/fuzz/README.md): each replays
# its committed corpus once, then fuzzes for a few seconds.  Only the
# fuzz suites run here: the build's other tests are the clang run's.
if [ "${NERF_TEST_FUZZ:-1}" = 0 ]; then
  :
elif echo "== fuzz: configure build/fuzz" &&
     ! nerf_configure build/fuzz --native-file scripts/native/clang.ini \
     --werror -Dfuzz=true -Dexamples=false -Dbench=false -Dviewer=disabled; then
  echo "== fuzz: meson setup failed (see build/fuzz/meson-logs/meson-log.txt)"
  failed=$((failed + 1))
elif ! meson compile -C build/fuzz; then
  echo "== fuzz: build failed"
  failed=$((failed + 1))
else
  for setup in replay fuzz; do
    echo "== fuzz: $setup"
    fuzz_log=build/fuzz/meson-logs/testlog-$setup.json
    rm -f "$fuzz_log"
    fuzz_rc=0
    before=$failed
    meson test -C build/fuzz --setup "$setup" --print-errorlogs \
      --suite "$([ "$setup" = replay ] && echo fuzz-replay || echo fuzz)" \
      || fuzz_rc=$?
    count_results "$fuzz_log"
    if [ "$fuzz_rc" -ne 0 ] && [ "$failed" -eq "$before" ]; then
      echo "== fuzz: meson test exited with status $fuzz_rc"
      failed=$((failed + 1))
    fi
  done
fi

# The fast suites cross-built for aarch64 and run under qemu-user: they
# prove that the x86-only code (AVX2/AVX-512 clones, AVX2 rounding, oneDNN) falls
# back cleanly.  On x86-64 hosts only; NERF_TEST_CROSS=0 leaves it out.
if [ "${NERF_TEST_CROSS:-1}" != 0 ] && [ "$(uname -m)" = x86_64 ]; then
  echo "== aarch64: scripts/cross-aarch64.sh"
  cross_log=build/aarch64/meson-logs/testlog.json
  rm -f "$cross_log"
  cross_rc=0
  ./scripts/cross-aarch64.sh ${user_args[@]+"${user_args[@]}"} || cross_rc=$?
  before=$failed
  count_results "$cross_log"
  if [ "$cross_rc" -ne 0 ] && [ "$failed" -eq "$before" ]; then
    echo "== aarch64: failed before its tests ran (status $cross_rc)"
    failed=$((failed + 1))
  fi
fi

if [ $((passed + failed + skipped)) -eq 0 ]; then
  echo "warning: no tests ran (check the arguments given to meson test)" >&2
fi
summary
[ "$failed" -eq 0 ]
