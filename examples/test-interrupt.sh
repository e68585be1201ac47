#!/bin/sh
# Ctrl-C, sent as a real SIGINT: nerf-train stops, saves and says so in one
# line (status 130, no "done"), and the model resumes at that step;
# nerf-render says which views are written and where (status 130), and
# the same command with --skip-existing renders only the missing ones.
#
#   test-interrupt.sh NERF-SCENE NERF-TRAIN NERF-RENDER
set -eu
scene=$1 train=$2 render=$3

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-interrupt.XXXXXX")
pid=
trap '[ -z "$pid" ] || kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

# wait_for WHAT TEST...: poll (up to a minute) until TEST succeeds.
wait_for() {
  what=$1
  shift
  tries=0
  until "$@"; do
    tries=$((tries + 1))
    [ "$tries" -lt 1200 ] || fail "timed out waiting for $what"
    kill -0 "$pid" 2>/dev/null || fail "ended before $what"
    sleep 0.05
  done
}

"$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }

# --- nerf-train: far more steps than it takes before the signal.
"$train" --data "$work/scene" --out "$work/model.nerf" --steps 100000000 \
  --batch 64 2>"$work/train.log" &
pid=$!
wait_for "the first step" grep -qs "step 1 " "$work/train.log"
kill -INT "$pid"
status=0
wait "$pid" || status=$?
pid=
[ "$status" -eq 130 ] || { cat "$work/train.log"; fail "train: status $status"; }
line=$(grep "interrupted" "$work/train.log") ||
  { cat "$work/train.log"; fail "train: no word of the interruption"; }
step=$(echo "$line" | sed -n "s|^nerf-train: interrupted at step \([0-9]*\); saved $work/model.nerf (resume with --resume)\$|\1|p")
[ -n "$step" ] || { cat "$work/train.log"; fail "train: message: $line"; }
[ "$(grep -c "interrupted" "$work/train.log")" -eq 1 ] ||
  { cat "$work/train.log"; fail "train: more than one line about it"; }
if grep -q "done in" "$work/train.log"; then
  cat "$work/train.log"
  fail "train: says done"
fi
"$train" --data "$work/scene" --out "$work/model.nerf" --batch 64 --resume \
  --steps $((step + 1)) 2>"$work/resume.log" ||
  { cat "$work/resume.log"; fail "train: resume"; }
grep -q "resuming $work/model.nerf at step $step\$" "$work/resume.log" ||
  { cat "$work/resume.log"; fail "train: not saved at step $step"; }

# --- nerf-render: many views, stopped once the first is written.
frames=400
# (exec: run in the background, $! is then nerf-render's own id.)
render_cmd() {
  exec "$render" --model "$work/model.nerf" --out "$work/frames" --path orbit \
    --frames "$frames" --width 32 --height 32 "$@"
}
(render_cmd 2>"$work/render.log") &
pid=$!
wait_for "the first view" test -e "$work/frames/r_000.png"
kill -INT "$pid"
status=0
wait "$pid" || status=$?
pid=
[ "$status" -eq 130 ] || { cat "$work/render.log"; fail "render: status $status"; }
n=$(ls "$work/frames" | grep -c '^r_[0-9]*\.png$' || true)
[ "$n" -ge 1 ] && [ "$n" -lt "$frames" ] ||
  fail "render: $n views written, not some of $frames"
ls "$work/frames" | grep -q '\.tmp' && fail "render: a temporary file was left"
last=$(printf 'r_%03d.png' $((n - 1)))
if [ "$n" -eq 1 ]; then
  wrote="1, r_000.png"
else
  wrote="$n, r_000.png to $last"
fi
grep -q "^nerf-render: interrupted: $work/frames holds $n of the $frames views (this run wrote $wrote); the same command with --skip-existing renders the other $((frames - n))\$" \
  "$work/render.log" || { cat "$work/render.log"; fail "render: message"; }

# --skip-existing: the views there are kept (same file, not rewritten),
# the others rendered; a smaller path keeps this fast.
frames=$((n + 2))
cp "$work/frames/r_000.png" "$work/first.png"
touch -d "2001-01-01" "$work/frames/r_000.png"
(render_cmd --skip-existing 2>"$work/rest.log") ||
  { cat "$work/rest.log"; fail "render --skip-existing"; }
grep -q "$n of the $frames views are in $work/frames already; rendering the other 2" \
  "$work/rest.log" || { cat "$work/rest.log"; fail "skip: message"; }
[ -z "$(find "$work/frames/r_000.png" -newer "$work/first.png")" ] ||
  fail "skip: r_000.png was rendered again"
for i in $(seq 0 $((frames - 1))); do
  [ -f "$(printf '%s/frames/r_%03d.png' "$work" "$i")" ] ||
    fail "skip: view $i missing"
done
(render_cmd --skip-existing 2>"$work/none.log") ||
  { cat "$work/none.log"; fail "render --skip-existing, all there"; }
grep -q "^nerf-render: all $frames views are in $work/frames already: nothing to render\$" \
  "$work/none.log" || { cat "$work/none.log"; fail "skip all: message"; }
echo "ok   Ctrl-C in nerf-train and nerf-render, and --skip-existing"
