#!/usr/bin/env bash
#
# From photos to a model in one command:
#
#   scripts/colmap-train.sh [options] PHOTOS_DIR OUT_DIR [-- nerf-train args]
#
# Runs COLMAP (Debian package `colmap`) on the CPU over the photos in
# PHOTOS_DIR -- feature extraction, exhaustive matching, mapping -- into
# OUT_DIR laid out as nerf_dataset_load() reads a COLMAP folder (images/
# and sparse/0/), then trains with `nerf-train --data OUT_DIR --out
# OUT_DIR/model.nerf` and any arguments after `--`.
#
# Options:
#   --camera-model M     COLMAP camera model for all photos (one camera):
#                        SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL (COLMAP's
#                        default), RADIAL or OPENCV
#   --min-registered N   fail when COLMAP places fewer than N photos
#                        (default: all of them)
#   --no-train           stop after COLMAP
#   --colmap PATH        the colmap program (default: $COLMAP, else colmap
#                        on PATH)
#   --nerf-train PATH    the nerf-train program (default: $NERF_TRAIN, else
#                        nerf-train on PATH, else build*/examples/nerf-train
#                        of this checkout)
#
# Exit status: 0 done; 1 COLMAP or nerf-train failed (the message says
# which stage and how many photos were placed); 2 bad arguments; 3 COLMAP
# is not installed.

set -u

me="colmap-train"
usage() {
  sed -n '3,28p' "$0" | sed 's/^# \{0,1\}//'
}

camera_model=SIMPLE_RADIAL
min_registered=""
train=1
nerf_train=${NERF_TRAIN:-}
colmap=${COLMAP:-colmap}
while [ $# -gt 0 ]; do
  case $1 in
    -h|--help) usage; exit 0 ;;
    --camera-model) camera_model=${2:-}; shift 2 || exit 2 ;;
    --min-registered) min_registered=${2:-}; shift 2 || exit 2 ;;
    --no-train) train=0; shift ;;
    --nerf-train) nerf_train=${2:-}; shift 2 || exit 2 ;;
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
photos=$1
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

if ! command -v "$colmap" >/dev/null 2>&1; then
  echo "$me: COLMAP is not installed (no '$colmap' found); on Debian:" \
       "sudo apt-get install colmap" >&2
  exit 3
fi
if [ ! -d "$photos" ]; then
  echo "$me: $photos: not a folder" >&2
  exit 2
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

# The photos, by name; COLMAP and the loader both see them in images/.
mkdir -p "$out/images" || exit 1
n=0
for f in "$photos"/*; do
  case ${f,,} in
    *.png|*.jpg|*.jpeg)
      cp -p "$f" "$out/images/" || exit 1
      n=$((n + 1)) ;;
  esac
done
if [ "$n" -lt 2 ]; then
  echo "$me: $photos: found $n photos (.png, .jpg, .jpeg); COLMAP needs" \
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

# stage NUMBER NAME COMMAND...: run one COLMAP stage with its output in
# colmap.log, timing it.
stage() {
  local number=$1 name=$2 start end
  shift 2
  echo "$me: [$number/4] $name ..."
  start=$(date +%s.%N)
  if ! "$@" >>"$log" 2>&1; then
    if [ "$number" = 3 ]; then
      echo "$me: COLMAP could not reconstruct the scene from the $n" \
           "photos: the mapper placed none (too few features matched" \
           "between them?); its output is in $log:" >&2
    else
      echo "$me: COLMAP $name failed; its output is in $log:" >&2
    fi
    grep -v '^$' "$log" | tail -n 3 >&2
    exit 1
  fi
  end=$(date +%s.%N)
  awk -v me="$me" -v k="$number" -v name="$name" -v a="$start" -v b="$end" \
    'BEGIN { printf "%s: [%s/4] %s done in %.1f s\n", me, k, name, b - a }'
}

stage 1 "feature extraction ($n photos)" \
  "$colmap" feature_extractor --database_path "$db" --image_path "$out/images" \
    --ImageReader.single_camera 1 --ImageReader.camera_model "$camera_model" \
    --SiftExtraction.use_gpu 0
stage 2 "exhaustive matching" \
  "$colmap" exhaustive_matcher --database_path "$db" --SiftMatching.use_gpu 0
stage 3 "mapping" \
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
  exit 1
fi
if [ "$best" != "$out/sparse/0" ]; then
  mv "$out/sparse/0" "$out/sparse/0.smaller" && mv "$best" "$out/sparse/0"
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
  if command -v nerf-train >/dev/null 2>&1; then
    nerf_train=nerf-train
  else
    here=$(cd "$(dirname "$0")/.." && pwd)
    for b in "$here"/build*/examples/nerf-train; do
      if [ -x "$b" ]; then
        nerf_train=$b
        break
      fi
    done
  fi
fi
if [ -z "$nerf_train" ]; then
  echo "$me: nerf-train not found (set --nerf-train PATH or NERF_TRAIN)" >&2
  exit 1
fi
echo "$me: [4/4] $nerf_train --data $out --out $out/model.nerf $*"
if ! "$nerf_train" --data "$out" --out "$out/model.nerf" "$@"; then
  echo "$me: nerf-train failed on $out" >&2
  exit 1
fi
