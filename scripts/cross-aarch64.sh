#!/usr/bin/env bash
#
# Cross build for 64-bit Arm Linux, tested under qemu-user:
#
#   ./scripts/cross-aarch64.sh [meson test arguments...]
#
# On a Debian machine: adds the arm64 architecture to dpkg and installs the
# cross compilers, qemu-user and the arm64 -dev packages (as root;
# otherwise prints the commands to run), configures build/aarch64 with
# scripts/cross/aarch64-linux-gnu.ini and --werror, builds it, and runs the
# suites abi, model and render with every program under qemu-aarch64.
# Extra arguments go to `meson test`.
#
# It proves that the x86-only parts fall back cleanly: the multiversioned
# loops (clones for AVX2 and AVX-512) and the AVX2 bf16 rounding
# are chosen by the build only on x86-64, and oneDNN (bf16) is x86-only,
# so it is disabled here.  The viewer (SDL2) and the API reference are not
# needed by these suites.
#
# Emulated floating point is 50 to 200 times slower than native, so test
# timeouts are multiplied (NERF_CROSS_TIMEOUT_MULTIPLIER, default 5).
# OpenBLAS runs on one thread (OPENBLAS_NUM_THREADS=1 unless set): its
# idle workers spin, which under emulation takes the two cores from the
# work; libnerf then spreads the products over its own workers instead
# (lib/mlp/gemm.h), as it does for any application that sets this.
# NERF_CROSS_JOBS (default: the number of processors) sets the build's and
# the tests' parallelism.
#
# The last line is "aarch64: N passed, N failed, N skipped"; the exit
# status is non-zero if the build or a test failed.

set -eu

cd "$(dirname "${BASH_SOURCE[0]}")/.."
# shellcheck source=scripts/deps.sh
. scripts/deps.sh

build=build/aarch64
cross_file=scripts/cross/aarch64-linux-gnu.ini
jobs=${NERF_CROSS_JOBS:-$(nproc 2>/dev/null || echo 2)}
multiplier=${NERF_CROSS_TIMEOUT_MULTIPLIER:-5}
OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
export OPENBLAS_NUM_THREADS

# The build machine's tools, then the host machine's libraries: libc6-dev
# for the dynamic loader qemu runs the programs with, the rest as in
# scripts/deps.sh.  nerf_ensure_packages installs this list.
NERF_DEB_PACKAGES=(meson ninja-build pkg-config python3
                   gcc-aarch64-linux-gnu g++-aarch64-linux-gnu qemu-user
                   libc6-dev:arm64 libopenblas-dev:arm64 libpng-dev:arm64
                   libjpeg-dev:arm64 zlib1g-dev:arm64 libcjson-dev:arm64)

passed=0
failed=0
skipped=0
summary() {
  echo "aarch64: $passed passed, $failed failed, $skipped skipped"
}

# add_arm64: make dpkg take arm64 packages (multiarch), as root; otherwise
# print the commands to run and fail.
add_arm64() {
  if dpkg --print-foreign-architectures | grep -qx arm64; then
    return 0
  fi
  if [ "$(id -u)" -ne 0 ]; then
    echo "cross-aarch64: dpkg does not take arm64 packages; run:" >&2
    echo "sudo dpkg --add-architecture arm64 && sudo apt-get update &&" \
         "sudo apt-get install -y ${NERF_DEB_PACKAGES[*]}"
    return 1
  fi
  echo "cross-aarch64: adding the arm64 architecture to dpkg" >&2
  dpkg --add-architecture arm64
}

if ! command -v dpkg >/dev/null 2>&1; then
  echo "cross-aarch64: needs a Debian system (dpkg, apt-get, multiarch)" >&2
  failed=1
  summary
  exit 1
fi
if ! add_arm64 || ! nerf_ensure_packages; then
  failed=1
  summary
  exit 1
fi

echo "== aarch64: configure $build"
if ! nerf_configure "$build" --cross-file "$cross_file" --werror \
     -Dbuildtype=release -Dbf16=disabled -Dviewer=disabled -Ddocs=disabled
then
  echo "== aarch64: meson setup failed (see $build/meson-logs/meson-log.txt)"
  failed=1
  summary
  exit 1
fi
echo "== aarch64: build"
if ! meson compile -C "$build" -j "$jobs"; then
  echo "== aarch64: build failed"
  failed=1
  summary
  exit 1
fi

echo "== aarch64: test (under qemu-aarch64)"
log=$build/meson-logs/testlog.json
rm -f "$log"
rc=0
meson test -C "$build" --suite abi --suite model --suite render \
  --num-processes "$jobs" --timeout-multiplier "$multiplier" \
  --print-errorlogs "$@" || rc=$?

# Meson's log holds one JSON object per test; quotes inside its strings
# are escaped, so a bare "result": "X" can only be the field itself.
if [ -s "$log" ]; then
  passed=$(grep -cE '"result": *"(OK|EXPECTEDFAIL)"' "$log" || true)
  skipped=$(grep -cE '"result": *"SKIP"' "$log" || true)
  failed=$(($(grep -cE '"result": *"[A-Z]+"' "$log" || true) - passed - skipped))
fi
if [ "$rc" -ne 0 ] && [ "$failed" -eq 0 ]; then
  # meson test failed without recording a failing test (a bad argument,
  # a rebuild error): count it so the run cannot look green.
  echo "== aarch64: meson test exited with status $rc"
  failed=1
fi
summary
[ "$failed" -eq 0 ]
