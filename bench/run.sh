#!/usr/bin/env bash
#
# Build the release nerf-bench and run it, then the PyTorch peer on the
# figures it wrote: ./bench/run.sh [nerf-bench options...]
#
#   NERF_BENCH_BUILD    build folder (default build/release)
#   NERF_BENCH_SECONDS  budget of each measurement (default 5)
#   NERF_BENCH_THREADS  threads for both libnerf and torch (default: cores)
#   PYTHON              interpreter with torch (default /usr/bin/python3)
#
# Results land in out/bench/: nerf-bench.json and peer.txt.  The peer needs
# python3-torch; without it only nerf-bench runs.

set -eu

cd "$(dirname "${BASH_SOURCE[0]}")/.."
# shellcheck source=scripts/deps.sh
. scripts/deps.sh

build=${NERF_BENCH_BUILD:-build/release}
seconds=${NERF_BENCH_SECONDS:-5}
threads=${NERF_BENCH_THREADS:-$(nproc)}
out=out/bench
mkdir -p "$out"

echo "== configure $build"
nerf_configure "$build" "${NERF_RELEASE_OPTIONS[@]}"
echo "== build nerf-bench"
meson compile -C "$build" nerf-bench

echo "== nerf-bench (load: $(cut -d' ' -f1-3 /proc/loadavg))"
# The table goes to stderr, the JSON to the file.
"$build/bench/nerf-bench" --json --preset all --seconds "$seconds" \
    --threads "$threads" --render-blas-threads 1 "$@" >"$out/nerf-bench.json"

# Debian's interpreter, which python3-torch installs into: the python3 first
# on PATH may be another one.
python=${PYTHON:-python3}
if [ -z "${PYTHON:-}" ] && [ -x /usr/bin/python3 ]; then
  python=/usr/bin/python3
fi
if "$python" -c 'import torch' 2>/dev/null; then
  echo "== PyTorch peer, reference preset"
  "$python" bench/torch_peer.py --nerf-json "$out/nerf-bench.json" \
      --preset reference --seconds "$seconds" --threads "$threads" |
    tee "$out/peer.txt"
else
  echo "== PyTorch peer skipped: python3 cannot import torch" \
       "(apt-get install python3-torch)"
fi
