#!/bin/sh
# nerf-train --out: missing folders are created (saying so), a path that
# cannot be written is refused before any training, and a final save that
# fails is reported as such (non-zero status, no "saved"), leaving the
# last good checkpoint in place.
#
#   test-train-out.sh NERF-SCENE NERF-TRAIN
set -eu
scene=$1 train=$2

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-train-out.XXXXXX")
trap 'chmod -R u+w "$work"; rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

"$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 0 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }

# refuse OUT WORDS: status 1, a message naming OUT and WORDS, and not a
# single step taken.
refuse() {
  out=$1 words=$2
  status=0
  "$train" --data "$work/scene" --out "$out" --steps 2 --batch 64 \
    2>"$work/bad.log" || status=$?
  [ "$status" -eq 1 ] || { cat "$work/bad.log"; fail "$out: status $status"; }
  grep -q "$out: cannot be written.*$words" "$work/bad.log" ||
    { cat "$work/bad.log"; fail "$out: message"; }
  if grep -q "done in" "$work/bad.log"; then
    cat "$work/bad.log"
    fail "$out: trained before refusing"
  fi
}
: >"$work/a-file"
refuse "$work/a-file/model.nerf" "Not a directory"
refuse "$work/a-file/sub/model.nerf" "Not a directory"
if [ "$(id -u)" -eq 0 ]; then
  echo "skip the read-only folder: root may write into any folder"
else
  mkdir "$work/read-only"
  chmod 555 "$work/read-only"
  refuse "$work/read-only/model.nerf" "Permission denied"
  refuse "$work/read-only/sub/model.nerf" "Permission denied"
fi

# Missing folders, parents included, are made as mkdir -p makes them, and
# said so.
"$train" --data "$work/scene" --out "$work/new/deeper/model.nerf" --steps 2 \
  --batch 64 2>"$work/new.log" || { cat "$work/new.log"; fail "new folder"; }
grep -q "created the folder $work/new/deeper" "$work/new.log" ||
  { cat "$work/new.log"; fail "new folder: not said"; }
[ -f "$work/new/deeper/model.nerf" ] || fail "new folder: no model"
ls "$work" | grep -q '\.tmp\.' && fail "the check left a temporary file"

# A good checkpoint, then runs whose final save fails: a file size limit
# (with SIGXFSZ ignored, so that writes fail with EFBIG) stops the write
# but not the check, which writes nothing.
"$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 2>"$work/train.log" || { cat "$work/train.log"; exit 1; }
cp "$work/model.nerf" "$work/good.nerf"

# limited ARGS...: nerf-train --resume under the limit; status in $status,
# stderr in limited.log (through a pipe: the limit applies to files).
limited() {
  (
    trap '' XFSZ
    ulimit -f 8
    status=0
    "$train" --data "$work/scene" --out "$work/model.nerf" --batch 64 \
      --resume "$@" 2>&1 || status=$?
    echo "status $status"
  ) | cat >"$work/limited.log"
  status=$(sed -n 's/^status //p' "$work/limited.log")
}
check_failed_save() {
  [ "$status" -ne 0 ] || { cat "$work/limited.log"; fail "$1: status 0"; }
  if grep -q "saved $work/model.nerf" "$work/limited.log"; then
    cat "$work/limited.log"
    fail "$1: claims the failed save"
  fi
  grep -q "NOT saved" "$work/limited.log" ||
    { cat "$work/limited.log"; fail "$1: no word of the failed save"; }
  cmp -s "$work/model.nerf" "$work/good.nerf" ||
    fail "$1: the last good checkpoint was not kept"
  ls "$work" | grep -q '\.tmp\.' && fail "$1: a temporary file was left"
  return 0
}
limited --steps 4
check_failed_save "--steps 4"
# Stopped by --seconds: the run itself ends as asked, the save does not.
limited --steps 100000000 --seconds 0.5
check_failed_save "--seconds"
echo "ok   nerf-train --out"
