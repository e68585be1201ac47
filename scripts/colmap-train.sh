#!/usr/bin/env bash
#
# From photos or a video to a model in one command:
#
#   scripts/colmap-train.sh [options] PHOTOS_DIR|VIDEO OUT_DIR [-- nerf-train args]
#
# Runs COLMAP (Debian package `colmap`) on the CPU over the photos in
# PHOTOS_DIR, or over photos of the video file VIDEO (nerf-frames takes
# the sharpest frame of each of --frames stretches of its time) --
# feature extraction, matching, mapping -- into OUT_DIR laid out as
# nerf_dataset_load() reads a COLMAP folder (images/ and sparse/0/), then
# trains with `nerf-train --data OUT_DIR --out OUT_DIR/model.nerf` and any
# arguments after `--`.  When COLMAP places fewer than all photos, the
# output names those left out, what is known of each and what usually
# helps (scripts/colmap-explain.py, from COLMAP's database).
#
# Options:
#   --camera-model M     COLMAP camera model for all photos (one camera):
#                        SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL (COLMAP's
#                        default), RADIAL or OPENCV
#   --matcher M          which pairs of photos COLMAP matches: exhaustive
#                        (every pair; the default for a folder) or
#                        sequential (each photo with its next ones in
#                        name order; the default for a video, whose
#                        frames are named in its order; cost grows with
#                        the count, not its square)
#   --frames N           photos to take from a VIDEO (default 150)
#   --min-registered N   fail when COLMAP places fewer than N photos
#                        (default: all of them)
#   --no-train           stop after COLMAP
#   --colmap PATH        the colmap program (default: $COLMAP, else colmap
#                        on PATH)
#   --nerf-train PATH    the nerf-train program (default: $NERF_TRAIN, else
#                        nerf-train on PATH, else build*/examples/nerf-train
#                        or build*/*/examples/nerf-train of this checkout)
#   --nerf-frames PATH   the nerf-frames program, for a VIDEO (default:
#                        $NERF_FRAMES, else as nerf-train)
#
# Exit status: 0 done; 1 COLMAP, nerf-frames or nerf-train failed (the
# message says which stage and how many photos were placed); 2 bad
# arguments; 3 COLMAP is not installed.

set -u

me="colmap-train"
usage() {
  sed -n '3,41p' "$0" | sed 's/^# \{0,1\}//'
}

camera_model=SIMPLE_RADIAL
matcher=""
frames=150
min_registered=""
train=1
nerf_train=${NERF_TRAIN:-}
nerf_frames=${NERF_FRAMES:-}
colmap=${COLMAP:-colmap}
while [ $# -gt 0 ]; do
  case $1 in
    -h|--help) usage; exit 0 ;;
    --camera-model) camera_model=${2:-}; shift 2 || exit 2 ;;
    --matcher) matcher=${2:-}; shift 2 || exit 2 ;;
    --frames) frames=${2:-}; shift 2 || exit 2 ;;
    --min-registered) min_registered=${2:-}; shift 2 || exit 2 ;;
    --no-train) train=0; shift ;;
    --nerf-train) nerf_train=${2:-}; shift 2 || exit 2 ;;
    --nerf-frames) nerf_frames=${2:-}; shift 2 || exit 2 ;;
    --colmap) colmap=${2:-}; shift 2 || exit 2 ;;
    --) break ;;
    -*) echo "$me: unknown option $1" >&2; usage >&2; exit 2 ;;
    *) break ;;
  esac
done
if [ $# -lt 2 ]; then
  usage >&2
  exit 2
fi
input=$1
out=$2
shift 2
if [ $# -gt 0 ] && [ "$1" = "--" ]; then
  shift
fi
case $camera_model in
  SIMPLE_PINHOLE|PINHOLE|SIMPLE_RADIAL|RADIAL|OPENCV) ;;
  *) echo "$me: --camera-model must be SIMPLE_PINHOLE, PINHOLE," \
          "SIMPLE_RADIAL, RADIAL or OPENCV (the models libnerf reads)" >&2
     exit 2 ;;
esac
case $matcher in
  ""|exhaustive|sequential) ;;
  *) echo "$me: --matcher must be exhaustive or sequential, not" \
          "'$matcher'" >&2
     exit 2 ;;
esac
case $frames in
  ''|*[!0-9]*|0) echo "$me: --frames needs a whole number of photos above" \
                      "0, not '$frames'" >&2
                 exit 2 ;;
esac

if ! command -v "$colmap" >/dev/null 2>&1; then
  echo "$me: COLMAP is not installed (no '$colmap' found); on Debian:" \
       "sudo apt-get install colmap" >&2
  exit 3
fi
# A folder of photos or a video file: what is not a folder is taken for a
# video, and nerf-frames says if it is not one.
if [ -d "$input" ]; then
  video=""
  matcher=${matcher:-exhaustive}
elif [ -f "$input" ]; then
  video=$input
  matcher=${matcher:-sequential}
else
  echo "$me: $input: neither a folder of photos nor a video file" >&2
  exit 2
fi

# find_program NAME: the path of an example program of this project: on
# PATH, else in a build of this checkout; "" when neither.
find_program() {
  local b here
  if command -v "$1" >/dev/null 2>&1; then
    echo "$1"
    return
  fi
  here=$(cd "$(dirname "$0")/.." && pwd)
  for b in "$here"/build*/examples/"$1" "$here"/build*/*/examples/"$1"; do
    if [ -x "$b" ]; then
      echo "$b"
      return
    fi
  done
}
if [ -n "$video" ] && [ -z "$nerf_frames" ]; then
  nerf_frames=$(find_program nerf-frames)
  if [ -z "$nerf_frames" ]; then
    echo "$me: nerf-frames not found (set --nerf-frames PATH or" \
         "NERF_FRAMES; it is built where FFmpeg's libraries are found)" >&2
    exit 1
  fi
fi
# New poses make an old model meaningless, so it is replaced only when
# asked, and asked before COLMAP's minute rather than after it.
if [ "$train" = 1 ] && [ -e "$out/model.nerf" ]; then
  case " $* " in
    *" --overwrite "*) ;;
    *) echo "$me: $out/model.nerf exists: add -- --overwrite to replace it" \
            "with a model of the new reconstruction" >&2
       exit 2 ;;
  esac
fi

# The stages, numbered as the run goes: the frames of a video, COLMAP's
# three, training.
stages=4
if [ -n "$video" ]; then
  stages=5
fi
at=0

# The photos, by name; COLMAP and the loader both see them in images/.
# A video's come from nerf-frames, named in the video's order, which
# sequential matching follows.
n=0
if [ -n "$video" ]; then
  at=$((at + 1))
  echo "$me: [$at/$stages] photos of $video ($nerf_frames, at most $frames)"
  # The photos of an earlier run, of another video maybe, are not this
  # one's.
  rm -rf "$out/images"
  mkdir -p "$out" || exit 1
  start=$(date +%s.%N)
  # frames.txt: which frame of the video each photo is (nerf-frames
  # --list), for a user who wants to find one.
  if ! "$nerf_frames" --video "$video" --out "$out/images" \
         --frames "$frames" --list >"$out/frames.txt"; then
    echo "$me: nerf-frames could not take the photos of $video" >&2
    exit 1
  fi
  for f in "$out/images"/*.jpg; do
    [ -f "$f" ] && n=$((n + 1))
  done
  end=$(date +%s.%N)
  awk -v me="$me" -v k="$at" -v s="$stages" -v n="$n" -v a="$start" \
      -v b="$end" 'BEGIN { printf "%s: [%s/%s] %d photos taken in %.1f s\n",
                           me, k, s, n, b - a }'
else
  mkdir -p "$out/images" || exit 1
  for f in "$input"/*; do
    case ${f,,} in
      *.png|*.jpg|*.jpeg)
        cp -p "$f" "$out/images/" || exit 1
        n=$((n + 1)) ;;
    esac
  done
fi
if [ "$n" -lt 2 ]; then
  echo "$me: $input: found $n photos (.png, .jpg, .jpeg); COLMAP needs" \
       "at least 2" >&2
  exit 1
fi
min_registered=${min_registered:-$n}
db=$out/database.db
log=$out/colmap.log
rm -f "$db" "$log"
rm -rf "$out/sparse"
mkdir -p "$out/sparse"

# No display is needed: COLMAP's CPU paths never open a window, but its Qt
# build looks for a platform plugin.
export QT_QPA_PLATFORM=${QT_QPA_PLATFORM:-offscreen}

here=$(cd "$(dirname "$0")" && pwd)
# explain KEPT: what colmap-explain.py says of the photos left out of the
# reconstruction KEPT ("" when there is none); nothing when it cannot run.
explain() {
  local python
  python=$(command -v python3 || true)
  [ -n "$python" ] && [ -f "$db" ] || return 0
  "$python" "$here/colmap-explain.py" "$db" "$out/sparse" "$1" "$matcher" |
    sed "s/^/$me: /"
}

# stage NAME COMMAND...: run one COLMAP stage with its output in
# colmap.log, timing it.
stage() {
  local name=$1 start end
  shift
  at=$((at + 1))
  echo "$me: [$at/$stages] $name ..."
  start=$(date +%s.%N)
  if ! "$@" >>"$log" 2>&1; then
    if [ "$name" = mapping ]; then
      echo "$me: COLMAP could not reconstruct the scene from the $n" \
           "photos: the mapper placed none (too few features matched" \
           "between them?); its output is in $log:" >&2
      grep -v '^$' "$log" | tail -n 3 >&2
      explain "" >&2
    else
      echo "$me: COLMAP $name failed; its output is in $log:" >&2
      grep -v '^$' "$log" | tail -n 3 >&2
    fi
    exit 1
  fi
  end=$(date +%s.%N)
  awk -v me="$me" -v k="$at" -v s="$stages" -v name="$name" -v a="$start" \
      -v b="$end" \
    'BEGIN { printf "%s: [%s/%s] %s done in %.1f s\n", me, k, s, name, b - a }'
}

stage "feature extraction ($n photos)" \
  "$colmap" feature_extractor --database_path "$db" --image_path "$out/images" \
    --ImageReader.single_camera 1 --ImageReader.camera_model "$camera_model" \
    --SiftExtraction.use_gpu 0
# Sequential: each photo with the next 10 in name order and, at 2, 4,
# 8 ... on (COLMAP's quadratic overlap), which bridges a blurred frame;
# no loop detection, which needs a vocabulary tree Debian does not ship.
if [ "$matcher" = sequential ]; then
  stage "sequential matching" \
    "$colmap" sequential_matcher --database_path "$db" \
      --SiftMatching.use_gpu 0
else
  stage "exhaustive matching" \
    "$colmap" exhaustive_matcher --database_path "$db" --SiftMatching.use_gpu 0
fi
stage mapping \
  "$colmap" mapper --database_path "$db" --image_path "$out/images" \
    --output_path "$out/sparse"

# The mapper may split the photos into several models (sparse/0, 1, ...):
# keep the one with most images as sparse/0, which the loader reads.
registered() {
  # images.bin starts with the image count, a little-endian uint64.
  od -An -t u8 -N 8 "$1/images.bin" 2>/dev/null | tr -d ' '
}
best=""
best_n=0
for m in "$out"/sparse/*/; do
  m=${m%/}
  [ -f "$m/images.bin" ] || continue
  k=$(registered "$m")
  if [ "${k:-0}" -gt "$best_n" ]; then
    best=$m
    best_n=$k
  fi
done
if [ -z "$best" ]; then
  echo "$me: COLMAP could not reconstruct the scene: the mapper placed no" \
       "photos (of $n); see $log" >&2
  explain "" >&2
  exit 1
fi
# Said before the kept model moves to sparse/0, under the mapper's names.
explain "${best##*/}"
if [ "$best" != "$out/sparse/0" ]; then
  mv "$out/sparse/0" "$out/sparse/0.smaller" && mv "$best" "$out/sparse/0"
  echo "$me: kept ${best##*/} as sparse/0 (the loader reads sparse/0);" \
       "the mapper's sparse/0 is now sparse/0.smaller"
fi
if [ "$best_n" -lt "$min_registered" ]; then
  echo "$me: COLMAP placed only $best_n of $n photos (need" \
       "$min_registered; --min-registered N accepts fewer)" >&2
  exit 1
fi
echo "$me: COLMAP placed $best_n of $n photos: $out/sparse/0"

if [ "$train" = 0 ]; then
  exit 0
fi
if [ -z "$nerf_train" ]; then
  nerf_train=$(find_program nerf-train)
fi
if [ -z "$nerf_train" ]; then
  echo "$me: nerf-train not found (set --nerf-train PATH or NERF_TRAIN)" >&2
  exit 1
fi
echo "$me: [$stages/$stages] $nerf_train --data $out --out $out/model.nerf $*"
if ! "$nerf_train" --data "$out" --out "$out/model.nerf" "$@"; then
  echo "$me: nerf-train failed on $out" >&2
  exit 1
fi
