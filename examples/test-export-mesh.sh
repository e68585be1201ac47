#!/bin/sh
# nerf-export mesh and grid on a model of the built-in scene trained a few
# steps: the grid is the shape the sidecar says, a mesh at a threshold the
# grid shows to be crossed has faces, and its PLY (binary and ASCII) and OBJ
# files load in an independent reader (python3-meshio; that part skipped
# with a message when it is absent) with the counts the program printed.
# Bad arguments exit 2 with one line; an unwritable output exits 1 naming
# the file.
#
#   test-export-mesh.sh NERF-SCENE NERF-TRAIN NERF-EXPORT PYTHON3
set -eu
scene=$1 train=$2 export=$3 python=$4
wrap=${MESON_EXE_WRAPPER:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/nerf-export-mesh.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  exit 1
}

$wrap "$scene" --out "$work/scene" --width 16 --height 16 --train 4 --val 0 \
  --test 1 2>"$work/scene.log" || { cat "$work/scene.log"; exit 1; }
# 8 + 16 samples a ray, not the tiny preset's 32 + 64: training pays
# for each, most of all under qemu.
$wrap "$train" --data "$work/scene" --out "$work/model.nerf" --steps 2 \
  --batch 64 --coarse-samples 8 --fine-samples 16 \
  2>"$work/train.log" || { cat "$work/train.log"; exit 1; }

# The grid, and a threshold between its low and high densities.
$wrap "$export" grid --model "$work/model.nerf" --out "$work/g.npy" \
  --resolution 12 --colour 2>"$work/grid.log" ||
  { cat "$work/grid.log"; fail "nerf-export grid"; }
threshold=$("$python" - "$work" <<'PY'
import json, sys
import numpy
work = sys.argv[1]
side = json.load(open(work + "/g.json"))
d = numpy.load(work + "/g.npy")
rgb = numpy.load(work + "/g_rgb.npy")
assert side["order"] == "zyx" and side["samples"] == "cell centres", side
assert list(d.shape) == side["shape"] == [12, 12, 12], (d.shape, side)
assert d.dtype == numpy.float32 and rgb.shape == (12, 12, 12, 3), rgb.shape
assert side["density"] == "g.npy" and side["colour"] == "g_rgb.npy", side
assert numpy.isfinite(d).all() and (d >= 0).all()
assert (rgb >= 0).all() and (rgb <= 1).all()
lo, hi = numpy.percentile(d, 20), numpy.percentile(d, 80)
assert hi > lo, "a flat density field: %g" % lo
print("%.9g" % ((lo + hi) / 2))
PY
) || fail "the grid files"

mesh() {
  out=$1
  shift
  $wrap "$export" mesh --model "$work/model.nerf" --out "$work/$out" \
    --resolution 16 --threshold "$threshold" "$@" 2>"$work/$out.log" ||
    { cat "$work/$out.log"; fail "nerf-export mesh --out $out $*"; }
  counts=$(sed -n 's/.*: \([0-9]*\) vertices, \([0-9]*\) triangles$/\1 \2/p' \
    "$work/$out.log")
  [ -n "$counts" ] || { cat "$work/$out.log"; fail "no counts printed"; }
  [ "${counts#* }" != 0 ] || { cat "$work/$out.log"; fail "no faces"; }
  echo "$out $counts" >>"$work/counts"
}
mesh m.ply
mesh a.ply --ascii
mesh m.obj
mesh big.ply --largest --no-colour
all=$(sed -n 's/^m.ply [0-9]* //p' "$work/counts")
largest=$(sed -n 's/^big.ply [0-9]* //p' "$work/counts")
[ "$largest" -le "$all" ] || fail "--largest has more faces than the mesh"

if "$python" -c "import meshio" 2>/dev/null; then
  "$python" - "$work" <<'PY' || fail "meshio read the files differently"
import sys
import meshio
work = sys.argv[1]
for line in open(work + "/counts"):
    name, nv, nf = line.split()
    m = meshio.read(work + "/" + name)
    faces = sum(len(c.data) for c in m.cells if c.type == "triangle")
    assert (len(m.points), faces) == (int(nv), int(nf)), \
        (name, len(m.points), faces, nv, nf)
PY
else
  echo "python3-meshio is not installed: the independent reader's check is" \
       "skipped (apt-get install python3-meshio)"
fi

# bad ARGS...: exit 2 and one line on stderr.
bad() {
  status=0
  $wrap "$export" "$@" >"$work/out" 2>"$work/err" || status=$?
  [ "$status" = 2 ] || { cat "$work/err"; fail "$* exited $status, not 2"; }
  [ "$(wc -l <"$work/err")" = 1 ] || { cat "$work/err"; fail "$*: not one line"; }
}
m="--model $work/model.nerf"
bad
bad mseh $m --out "$work/x.ply"
grep -q "did you mean mesh" "$work/err" || { cat "$work/err"; fail "no hint"; }
bad mesh $m --out "$work/x.ply" --resolution 0
grep -q "resolution" "$work/err" || fail "resolution 0 not named"
bad mesh $m --out "$work/x.ply" --box 0,0,0,0,1,1
bad mesh $m --out "$work/x.ply" --threshold nan
bad mesh $m --out "$work/x.ply" --resoluton 8
grep -q "did you mean --resolution" "$work/err" || { cat "$work/err"; fail "no hint"; }
bad mesh $m --out "$work/x.stl"
bad mesh $m --out "$work/x.obj" --ascii
bad mesh --out "$work/x.ply"
bad grid $m --out "$work/x.npy" --threshold 3

# An unwritable output: a path through a regular file.
touch "$work/file"
status=0
$wrap "$export" mesh $m --out "$work/file/x.ply" 2>"$work/err" || status=$?
[ "$status" = 1 ] || { cat "$work/err"; fail "unwritable --out exited $status"; }
grep -q "file/x.ply" "$work/err" || { cat "$work/err"; fail "file not named"; }

# --help: stdout only, exit 0, with examples.
for sub in mesh grid; do
  $wrap "$export" $sub --help >"$work/help" 2>"$work/err" ||
    fail "$sub --help failed"
  [ ! -s "$work/err" ] || fail "$sub --help wrote to stderr"
  grep -q "^Examples:" "$work/help" || fail "$sub --help has no examples"
  grep -q "default" "$work/help" || fail "$sub --help states no default"
done
$wrap "$export" --help | grep -q "^  mesh " || fail "nerf-export --help"
echo "ok"
