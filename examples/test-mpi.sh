#!/bin/sh
# nerf-train-mpi and nerf-render-mpi under mpirun with two ranks: two runs
# with the same seed write the same checkpoint byte for byte; a two-rank
# checkpoint resumes in one process (nerf-train) and a one-process one
# with two ranks; a rank killed mid-run ends the job with an error, not a
# hang, and rank 0's last checkpoint still loads; nerf-render-mpi writes
# the frames nerf-render writes, byte for byte.  Skipped (77) without MPI.
#
#   test-mpi.sh NERF-SCENE NERF-TRAIN NERF-RENDER NERF-INFO
#               [NERF-TRAIN-MPI NERF-RENDER-MPI MPIRUN]
set -eu
if [ $# -lt 7 ]; then
  echo "SKIP: built without Open MPI (install libopenmpi-dev and" \
       "openmpi-bin, then reconfigure: meson setup --reconfigure)"
  exit 77
fi
scene=$1 train=$2 render=$3 info=$4 train_mpi=$5 render_mpi=$6 mpirun=$7
wrap=${MESON_EXE_WRAPPER:-}
# CI runs as root; two ranks on fewer cores need --oversubscribe.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-mpi.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

if ! "$mpirun" -np 2 true >"$work/pre.log" 2>&1; then
  cat "$work/pre.log"
  echo "SKIP: mpirun cannot start two processes here"
  exit 77
fi

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 \
  --val 0 --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }

# train2 OUT ARGS...: two ranks train the scene into OUT.
train2() {
  out=$1
  shift
  "$mpirun" -np 2 $wrap "$train_mpi" --data "$work/scene" --out "$out" \
    --batch 64 --seed 3 "$@" 2>"$out.log" || { cat "$out.log"; fail "$out"; }
}

# Same seed, same worker count: the same bits.
train2 "$work/a.nerf" --steps 6 --checkpoint-every 3
train2 "$work/b.nerf" --steps 6 --checkpoint-every 3
cmp "$work/a.nerf" "$work/b.nerf" || fail "two runs differ"
grep -q "2 ranks; rank 0 spent" "$work/a.nerf.log" ||
  { cat "$work/a.nerf.log"; fail "no exchange report"; }
# Rank 0 alone reports progress and saves.
[ "$(grep -c "saved .*a.nerf at step 6" "$work/a.nerf.log")" -eq 1 ] ||
  { cat "$work/a.nerf.log"; fail "not one save at step 6"; }

# A two-rank checkpoint resumes in one process, and a one-process one
# with two ranks.
$wrap "$train" --data "$work/scene" --out "$work/a.nerf" --batch 64 \
  --seed 3 --resume --steps 9 2>"$work/resume1.log" ||
  { cat "$work/resume1.log"; fail "resume in one process"; }
grep -q "resuming .* at step 6" "$work/resume1.log" || fail "resume1 log"
train2 "$work/a.nerf" --resume --steps 12
grep -q "resuming .* at step 9" "$work/a.nerf.log" ||
  { cat "$work/a.nerf.log"; fail "resume with two ranks"; }
$wrap "$info" "$work/a.nerf" >"$work/info.txt" 2>&1 ||
  { cat "$work/info.txt"; fail "nerf-info"; }
grep -q "^step *12$" "$work/info.txt" || { cat "$work/info.txt"; fail "step 12"; }

# A time budget fits the run to one process's clock: refused.
status=0
"$mpirun" -np 2 $wrap "$train_mpi" --data "$work/scene" \
  --out "$work/budget.nerf" --seconds 5 2>"$work/budget.log" || status=$?
[ "$status" -ne 0 ] || fail "--seconds without --steps was accepted"
grep -q "give --steps" "$work/budget.log" || { cat "$work/budget.log"; fail "budget message"; }

# Frames split across ranks are the frames of one process.
$wrap "$render" --model "$work/a.nerf" --out "$work/r1" --path orbit \
  --frames 5 --width 12 --height 10 2>"$work/r1.log" ||
  { cat "$work/r1.log"; fail "nerf-render"; }
"$mpirun" -np 2 $wrap "$render_mpi" --model "$work/a.nerf" --out "$work/r2" \
  --path orbit --frames 5 --width 12 --height 10 2>"$work/r2.log" ||
  { cat "$work/r2.log"; fail "nerf-render-mpi"; }
for f in "$work"/r1/*; do
  cmp "$f" "$work/r2/$(basename "$f")" || fail "frame $(basename "$f")"
done
[ "$(ls "$work/r1" | wc -l)" -eq 5 ] && [ "$(ls "$work/r2" | wc -l)" -eq 5 ] ||
  fail "frame counts"

# A rank killed mid-run ends the job with an error within the timeout,
# and the last checkpoint rank 0 wrote still loads.  (Not under an
# emulator, whose processes are not the programs themselves.)
if [ -n "$wrap" ]; then
  echo "ok (the killed-rank case skipped under $wrap)"
  exit 0
fi
"$mpirun" -np 2 "$train_mpi" --data "$work/scene" --out "$work/kill.nerf" \
  --batch 64 --steps 1000000 --checkpoint-every 5 2>"$work/kill.log" &
job=$!
rank1=
for _ in $(seq 600); do
  if [ -f "$work/kill.nerf" ] && [ -z "$rank1" ]; then
    for p in $(pgrep -f "$work/kill.nerf" || true); do
      if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null |
          grep -qx "OMPI_COMM_WORLD_RANK=1"; then
        rank1=$p
      fi
    done
  fi
  [ -n "$rank1" ] && break
  sleep 0.1
done
[ -n "$rank1" ] || { kill "$job"; fail "rank 1 not found"; }
kill -9 "$rank1"
# mpirun must end the job on its own: give it 60 s, then call it a hang.
(
  for _ in $(seq 600); do
    kill -0 "$job" 2>/dev/null || exit 0
    sleep 0.1
  done
  touch "$work/hung"
  kill -9 "$job"
) >/dev/null 2>&1 &
status=0
wait "$job" || status=$?
[ ! -f "$work/hung" ] || { cat "$work/kill.log"; fail "hang: the job had to be killed"; }
[ "$status" -ne 0 ] || fail "the job ended well after a rank was killed"
grep -qi "rank 1\|signal 9\|killed" "$work/kill.log" ||
  { cat "$work/kill.log"; fail "no message naming the dead rank"; }
$wrap "$info" "$work/kill.nerf" >"$work/kill-info.txt" 2>&1 ||
  { cat "$work/kill-info.txt"; fail "the last checkpoint does not load"; }
echo "ok"
