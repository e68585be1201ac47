"""nerf.Model.mesh and Model.write_density_grid (libnerf 0.5): arrays of
the right shapes and types, colours as the model sees the surface, a grid
equal to the model's density at the cell centres, files an independent
reader loads, progress, cancelling and bad arguments."""

import array
import json
import math
import os

import _support
from _support import TestCase, flat, nerf, shape


def npy_floats(path):
    """The float32 data of a version 1.0 .npy, without NumPy."""
    with open(path, "rb") as f:
        data = f.read()
    header = 10 + int.from_bytes(data[8:10], "little")
    values = array.array("f")
    values.frombytes(data[header:])
    return list(values)


def model_and_threshold():
    """A tiny model (random weights, whose density varies over the box)
    and the median of its density on a coarse grid: a level it crosses."""
    model = nerf.Model(preset="tiny", seed=2)
    path = os.path.join(_support.tmpdir(), "coarse.npy")
    model.write_density_grid(path, resolution=8)
    values = sorted(npy_floats(path))
    assert values[0] < values[-1], "a flat density field"
    return model, values[len(values) // 2]


class Mesh(TestCase):
    def test_arrays(self):
        model, threshold = model_and_threshold()
        with model:
            mesh = model.mesh(resolution=12, threshold=threshold)
            nv, nf = mesh.vertex_count, mesh.face_count
            self.assertGreater(nf, 0)
            self.assertEqual(shape(mesh.vertices), (nv, 3))
            self.assertEqual(shape(mesh.faces), (nf, 3))
            self.assertEqual(shape(mesh.colours), (nv, 3))
            self.assertEqual(shape(mesh.normals), (nv, 3))
            self.assertTrue(all(0 <= i < nv for i in flat(mesh.faces)))
            if nerf.HAVE_NUMPY:
                import numpy as np
                self.assertEqual(mesh.vertices.dtype, np.float32)
                self.assertEqual(mesh.faces.dtype, np.uint32)
                self.assertEqual(mesh.colours.dtype, np.uint8)
            # The colour of each vertex is the model's, seen along minus
            # its normal (the documented rule), rounded to bytes.
            v = [flat(mesh.vertices)[3 * i:3 * i + 3] for i in range(nv)]
            n = [flat(mesh.normals)[3 * i:3 * i + 3] for i in range(nv)]
            d = [[-c for c in x] if any(x) else [0.0, 0.0, -1.0] for x in n]
            rgb, _ = model.query(v, d)
            want = [round(255 * min(1.0, max(0.0, c))) for c in flat(rgb)]
            got = flat(mesh.colours)
            self.assertLessEqual(max(abs(a - b) for a, b in zip(got, want)),
                                 1)
            plain = model.mesh(resolution=12, threshold=threshold,
                               colour=False, keep_largest=True)
            self.assertIsNone(plain.colours)
            self.assertLessEqual(plain.face_count, nf)

    def test_files(self):
        model, threshold = model_and_threshold()
        with model:
            mesh = model.mesh(resolution=10, threshold=threshold)
        folder = _support.tmpdir()
        for name, fmt in (("m.ply", "auto"), ("a.ply", "ply_ascii"),
                          ("m.obj", "auto")):
            path = os.path.join(folder, name)
            mesh.write(path, fmt)
            self.assertGreater(os.path.getsize(path), 0)
            try:
                import meshio
            except ImportError:
                continue
            m = meshio.read(path)
            faces = sum(len(c.data) for c in m.cells if c.type == "triangle")
            self.assertEqual((len(m.points), faces),
                             (mesh.vertex_count, mesh.face_count))
        with self.assertRaises(ValueError):
            mesh.write(os.path.join(folder, "x.ply"), "stl")
        with self.assertNerfError(nerf.NerfIOError, nerf.EIO, "no/such"):
            mesh.write(os.path.join(folder, "no/such/x.ply"))

    def test_progress_and_cancel(self):
        model, threshold = model_and_threshold()
        seen = []
        with model:
            model.mesh(resolution=8, threshold=threshold,
                       progress=seen.append)
            self.assertEqual([p.done for p in seen], list(range(1, 10)))
            self.assertEqual({p.kind for p in seen}, {"geometry"})
            with self.assertRaises(nerf.NerfCancelled):
                model.mesh(resolution=8, progress=lambda p: p.done >= 3)

            def boom(p):
                raise KeyError("from the callback")
            with self.assertRaises(KeyError):
                model.mesh(resolution=8, progress=boom)

    def test_bad_arguments(self):
        with nerf.Model(preset="tiny") as model:
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "resolution"):
                model.mesh(resolution=0)
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "volume"):
                model.mesh(box=(0, 0, 0, 1, 0, 1))
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "threshold"):
                model.mesh(threshold=math.nan)
            with self.assertRaises(ValueError):
                model.mesh(box=(0, 0, 1))


class DensityGrid(TestCase):
    def test_grid(self):
        folder = _support.tmpdir()
        path = os.path.join(folder, "grid.npy")
        with nerf.Model(preset="tiny", seed=2) as model:
            side = model.write_density_grid(path, resolution=6,
                                            box=(-1, -1, -0.5, 1, 1, 0.5))
            self.assertEqual(side["shape"], [3, 6, 6])
            self.assertEqual(side["order"], "zyx")
            self.assertEqual(side["box_min"], [-1, -1, -0.5])
            with open(os.path.join(folder, "grid.json")) as f:
                self.assertEqual(json.load(f), side)
            if not nerf.HAVE_NUMPY:
                return
            import numpy as np
            grid = np.load(path)
            self.assertEqual(grid.shape, (3, 6, 6))
            # The cell centres as the library computes them, in float32
            # (lo + (i + 0.5) * step): the very points it sampled, since
            # the encoding's highest frequency would turn a last-bit
            # difference in a position into one 512 times larger.
            f32 = np.float32
            lo = np.array(side["box_min"], dtype=f32)
            step = np.array(side["spacing"], dtype=f32)
            centre = [lo[a] + (np.arange(n, dtype=f32) + f32(0.5)) * step[a]
                      for a, n in enumerate((6, 6, 3))]
            z, y, x = np.meshgrid(centre[2], centre[1], centre[0],
                                  indexing="ij")
            pts = np.stack([x, y, z], axis=-1).reshape(-1, 3)
            _, sigma = model.query(pts, np.tile([0, 0, 1.0], (len(pts), 1)))
            want = np.maximum(sigma, 0).reshape(3, 6, 6)
            # The grid's density pass and the query make products of other
            # shapes (planes of 36 points, a density column alone), whose
            # sums may run in other orders: each of the tiny network's
            # products of at most 91 terms is within gamma(93) = 5.5e-6 of
            # exact relative to its terms' magnitudes, far below a
            # thousandth of the largest density.
            self.assertTrue(np.allclose(grid, want, rtol=0,
                                        atol=1e-3 * float(np.max(want))))


if __name__ == "__main__":
    _support.main()
