#!/bin/sh
# Data-parallel training measured on this machine (docs/distributed.md):
# for the fast and reference presets, one process with two threads
# (nerf-train) against two ranks of one core each (mpirun -np 2 --bind-to
# core nerf-train-mpi, the fast preset with the dense and the sparse
# exchange), steps per second and the share of rank 0's time spent in the
# gradient exchange.  Both start from the same checkpoint, trained past
# the occupancy grid's warm-up, so the figures are those of a settled run.
#
#   scripts/bench-mpi.sh [BUILD [FAST_STEPS [REFERENCE_STEPS]]]
#   (defaults: build, 200, 10; FAST_WARM=N: warm-up steps of fast, 300)
#
# A timed benchmark: run it on an otherwise idle machine.
set -eu
build=${1:-build}
fast_steps=${2:-200}
ref_steps=${3:-10}
bin="$build/examples"
for p in nerf-scene nerf-train nerf-train-mpi; do
  [ -x "$bin/$p" ] || { echo "bench-mpi: no $bin/$p (built with Open MPI?)"; exit 1; }
done
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d "${TMPDIR:-/tmp}/bench-mpi.XXXXXX")
trap 'rm -rf "$work"' EXIT

"$bin/nerf-scene" --out "$work/scene" 2>/dev/null

# seconds LOG: the run's wall time, from its last line ("done in 12.3s").
seconds() {
  sed -n 's/.*done in \([0-9.]*\)s.*/\1/p' "$1" | tail -1
}
# exchange LOG: rank 0's seconds in the gradient exchange.
exchange() {
  sed -n 's/.*rank 0 spent \([0-9.]*\) s in.*/\1/p' "$1" | tail -1
}

printf '%-10s %-34s %9s %8s %14s\n' preset run steps/s "s/step" "exchange share"
# bench PRESET WARM STEPS BATCH
bench() {
  preset=$1 warm=$2 steps=$3 batch=$4
  start="$work/$preset-start.nerf"
  "$bin/nerf-train" --data "$work/scene" --out "$start" --preset "$preset" \
    --batch "$batch" --steps "$warm" 2>/dev/null
  total=$((warm + steps))
  # one NAME ENV... -- COMMAND...: time COMMAND from the warm checkpoint.
  one() {
    name=$1
    shift
    cp "$start" "$work/run.nerf"
    env "$@" --data "$work/scene" --out "$work/run.nerf" --resume \
      --batch "$batch" --steps "$total" --checkpoint-every 0 \
      >"$work/log" 2>&1 || { cat "$work/log"; exit 1; }
    s=$(seconds "$work/log")
    x=$(exchange "$work/log")
    awk -v p="$preset" -v n="$name" -v s="$s" -v k="$steps" -v x="${x:-0}" \
      'BEGIN { printf "%-10s %-34s %9.2f %8.3f %13.1f%%\n", p, n, k / s,
               s / k, 100 * x / s }'
  }
  one "1 process, 2 threads" "$bin/nerf-train"
  one "2 ranks x 1 core" NERF_MPI_EXCHANGE=auto \
    mpirun -np 2 --bind-to core "$bin/nerf-train-mpi"
  if [ "$preset" = fast ]; then
    one "2 ranks x 1 core, dense exchange" NERF_MPI_EXCHANGE=dense \
      mpirun -np 2 --bind-to core -x NERF_MPI_EXCHANGE "$bin/nerf-train-mpi"
    one "2 ranks x 1 core, sparse exchange" NERF_MPI_EXCHANGE=sparse \
      mpirun -np 2 --bind-to core -x NERF_MPI_EXCHANGE "$bin/nerf-train-mpi"
  fi
}
bench fast "${FAST_WARM:-300}" "$fast_steps" 1024
bench reference 2 "$ref_steps" 1024
