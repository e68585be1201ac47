#!/bin/sh
# nerf-train --seconds without --steps fits the run's length to the time,
# records it in MODEL (nerf-info shows it) and --resume goes on to it;
# --steps with --seconds stops at whichever comes first and says which;
# --resume without --steps continues to the steps MODEL was given;
# --lr-final sets the rate the schedule ends at.
#
#   test-train-budget.sh NERF-SCENE NERF-TRAIN NERF-INFO
set -eu
scene=$1 train=$2 info=$3

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-train-budget.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

"$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }

# run MODEL LOG ARGS...: nerf-train on the scene; status in $status.
run() {
  model=$1 log=$2
  shift 2
  status=0
  "$train" --data "$work/scene" --out "$work/$model" --batch 32 "$@" \
    2>"$work/$log" || status=$?
}
# key MODEL NAME: a field of nerf-info's schedule.
key() {
  "$info" "$work/$1" --json | tr -d ' \t\n' |
    sed -n "s/.*\"schedule\":{[^}]*\"$2\":\([^,}]*\).*/\1/p" | tr -d '"'
}

# Two seconds, not one: on an overloaded machine (three jobs on two
# cores) a one-second budget once fitted its length at the step it
# measured after, leaving no step to decay over.
run budget.nerf budget.log --seconds 2
[ "$status" -eq 0 ] || { cat "$work/budget.log"; fail "budget: status $status"; }
grep -q "training for 2 s" "$work/budget.log" ||
  { cat "$work/budget.log"; fail "budget: no opening line"; }
[ "$(key budget.nerf kind)" = fitted ] || fail "budget: schedule not fitted"
total=$(key budget.nerf steps)
start=$(key budget.nerf decay_start)
[ "$total" -gt "$start" ] && [ "$start" -gt 0 ] ||
  { cat "$work/budget.log"; fail "budget: decay from $start to $total"; }
step=$("$info" "$work/budget.nerf" | sed -n 's/^step *//p')
if [ "$step" -lt "$total" ]; then
  # The steps after the fit ran slower than measured (a busy machine):
  # out of time, said so, and --resume goes on to the fitted length.
  grep -q "out of time" "$work/budget.log" ||
    { cat "$work/budget.log"; fail "budget: stopped short silently"; }
  run budget.nerf resume.log --resume
  [ "$status" -eq 0 ] || { cat "$work/resume.log"; fail "resume: status"; }
  step=$("$info" "$work/budget.nerf" | sed -n 's/^step *//p')
fi
[ "$step" -eq "$total" ] || fail "budget: step $step, fitted $total"
# Done: resuming it trains nothing.
run budget.nerf done.log --resume
[ "$status" -eq 0 ] || { cat "$work/done.log"; fail "done: status"; }
grep -q "already at step $total" "$work/done.log" ||
  { cat "$work/done.log"; fail "done: message"; }

# --steps and --seconds: the steps come first here, and it is said.
run both.nerf both.log --steps 3 --seconds 600
[ "$status" -eq 0 ] || { cat "$work/both.log"; fail "both: status"; }
grep -q "stopping at step 3 or after 600 s, whichever comes first" \
  "$work/both.log" || { cat "$work/both.log"; fail "both: opening line"; }
grep -q "reached step 3 before the 600 s limit" "$work/both.log" ||
  { cat "$work/both.log"; fail "both: closing line"; }
[ "$(key both.nerf kind)" = steps ] || fail "both: not a steps schedule"

# --resume without --steps: on to the steps MODEL was given (3), not the
# default 2000.
run both.nerf again.log --resume
grep -q "already at step 3" "$work/again.log" ||
  { cat "$work/again.log"; fail "resume: went past the given steps"; }
# --lr and --lr-final set the schedule's ends, which the model records.
run rates.nerf rates.log --steps 2 --lr 0.02 --lr-final 0.0005
[ "$status" -eq 0 ] || { cat "$work/rates.log"; fail "rates: status"; }
[ "$(key rates.nerf lr)" = 0.02 ] &&
  [ "$(key rates.nerf lr_final)" = 0.0005 ] ||
  fail "rates: lr $(key rates.nerf lr), lr_final $(key rates.nerf lr_final)"
run rates.nerf default.log --steps 2 --lr 0.02 --overwrite
[ "$(key rates.nerf lr_final)" = 0.002 ] ||
  fail "rates: default lr_final $(key rates.nerf lr_final), not a tenth"
echo "ok: fitted $start..$total"
