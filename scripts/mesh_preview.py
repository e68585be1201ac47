#!/usr/bin/env python3
"""Draw a model's mesh, as nerf-export mesh extracts it, as a PNG.

    /usr/bin/python3 scripts/mesh_preview.py MODEL OUT.png [--resolution N]
        [--size PIXELS] [--azimuth DEG] [--elevation DEG]

Extracts the mesh through the Python binding (Model.mesh()), then draws it
with NumPy alone: every triangle is sampled at points spread over it
(more for larger triangles), the points are projected orthographically
and kept nearest-first in a depth buffer, and each pixel is shaded with
its triangle's vertex colours times a Lambert term of the face normal
against a light over the viewer's shoulder.  No mesh viewer or OpenGL is
needed, so it runs on a headless machine.
"""

import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "bindings", "python"))

import nerf  # noqa: E402


def rotation(azimuth, elevation):
    """World to view: z toward the viewer, y up."""
    a, e = math.radians(azimuth), math.radians(elevation)
    rz = np.array([[math.cos(a), -math.sin(a), 0.0],
                   [math.sin(a), math.cos(a), 0.0],
                   [0.0, 0.0, 1.0]])
    # Blender scenes are z-up: look at them from the side, tilted down.
    tilt = e - math.pi / 2
    rx = np.array([[1.0, 0.0, 0.0],
                   [0.0, math.cos(tilt), -math.sin(tilt)],
                   [0.0, math.sin(tilt), math.cos(tilt)]])
    return rx @ rz


def splat(v, f, c, size):
    """Depth-buffered points sampled over every triangle."""
    a, b, d = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, d - a)
    area = np.linalg.norm(n, axis=1)
    n = n / np.maximum(area, 1e-12)[:, None]
    span = max(np.ptp(v[:, 0]), np.ptp(v[:, 1])) * 1.05
    lo = (v[:, :2].min(0) + v[:, :2].max(0)) / 2 - span / 2
    pixel = span / size
    # Enough samples that neighbouring ones fall on neighbouring pixels.
    per = np.clip(np.ceil(area / 2 / pixel ** 2 * 2), 1, 64).astype(int)
    tri = np.repeat(np.arange(len(f)), per)
    rng = np.random.default_rng(0)
    r1, r2 = rng.random(len(tri)), rng.random(len(tri))
    flip = r1 + r2 > 1
    r1[flip], r2[flip] = 1 - r1[flip], 1 - r2[flip]
    w0 = 1 - r1 - r2
    p = (w0[:, None] * a[tri] + r1[:, None] * b[tri] + r2[:, None] * d[tri])
    col = (w0[:, None] * c[f[tri, 0]] + r1[:, None] * c[f[tri, 1]] +
           r2[:, None] * c[f[tri, 2]])
    light = np.array([0.4, 0.5, 0.77])
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.abs(n[tri] @ light)
    ix = ((p[:, 0] - lo[0]) / pixel).astype(int)
    iy = (size - 1 - (p[:, 1] - lo[1]) / pixel).astype(int)
    ok = (ix >= 0) & (ix < size) & (iy >= 0) & (iy < size)
    ix, iy, z = ix[ok], iy[ok], p[ok, 2]
    col, shade = col[ok], shade[ok]
    # Nearest first (largest z toward the viewer), then one per pixel.
    order = np.lexsort((-z, iy * size + ix))
    key = (iy * size + ix)[order]
    first = np.ones(len(key), bool)
    first[1:] = key[1:] != key[:-1]
    pick = order[first]
    image = np.ones((size * size, 3), np.float32)
    image[key[first]] = np.clip(col[pick] * shade[pick, None], 0, 1)
    return image.reshape(size, size, 3)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model")
    ap.add_argument("out")
    ap.add_argument("--resolution", type=int, default=256)
    ap.add_argument("--size", type=int, default=640)
    ap.add_argument("--azimuth", type=float, default=-35.0)
    ap.add_argument("--elevation", type=float, default=25.0)
    args = ap.parse_args()
    with nerf.Model.load(args.model) as model:
        mesh = model.mesh(resolution=args.resolution, keep_largest=True)
    v = np.asarray(mesh.vertices, np.float64)
    f = np.asarray(mesh.faces, np.int64)
    c = np.asarray(mesh.colours, np.float64) / 255.0
    v = v @ rotation(args.azimuth, args.elevation).T
    image = splat(v, f, c, args.size)
    nerf.write_png(args.out, image)
    print("%s: %d vertices, %d faces drawn at %dx%d" %
          (args.out, len(v), len(f), args.size, args.size))


if __name__ == "__main__":
    main()
