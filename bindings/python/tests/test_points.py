"""World-unit depth maps (no copy) and point clouds (libnerf 0.5)."""

import ctypes
import math
import os
import struct

import _support
from _support import TestCase, flat, nerf, shape


def camera(size=12):
    return nerf.Camera.from_fov(size, size, 40.0, eye=(0.0, -4.0, 1.0))


def read_ply(path):
    """(count, rows) of a PLY written by libnerf, read by an independent
    reader when one is installed, else by this minimal one."""
    for name in ("meshio", "open3d", "plyfile"):
        try:
            mod = __import__(name)
        except ImportError:
            continue
        if name == "meshio":
            mesh = mod.read(path)
            return len(mesh.points), [list(p) for p in mesh.points]
        if name == "open3d":
            pc = mod.io.read_point_cloud(path)
            pts = [list(p) for p in pc.points]
            return len(pts), pts
        data = mod.PlyData.read(path)["vertex"]
        return data.count, [[v["x"], v["y"], v["z"]] for v in data]
    print("note: no independent PLY reader (meshio, open3d, plyfile) for "
          "/usr/bin/python3; reading %s with the test's own parser"
          % os.path.basename(path))
    with open(path, "rb") as f:
        blob = f.read()
    head, body = blob.split(b"end_header\n", 1)
    lines = head.decode("ascii").splitlines()
    count = int([ln for ln in lines if ln.startswith("element vertex")][0]
                .split()[2])
    rows = []
    if "format ascii 1.0" in lines:
        for ln in body.decode("ascii").splitlines():
            rows.append([float(v) for v in ln.split()[:3]])
    else:
        for i in range(count):
            rows.append(list(struct.unpack_from("<3f", body, 27 * i)))
        if len(body) != 27 * count:
            raise AssertionError("body of %d bytes for %d vertices"
                                 % (len(body), count))
    return count, rows


class Depth(TestCase):
    @classmethod
    def setUpClass(cls):
        cls.model = nerf.Model(preset="tiny", seed=7)
        cls.renderer = nerf.Renderer(
            cls.model, nerf.Sampler(preset="tiny", n_coarse=8, n_fine=8))

    def test_depths_agree_with_render_and_rays(self):
        cam = camera()
        raw = self.renderer.render_image(cam)
        res = self.renderer.render_depth(cam)
        self.assertEqual(shape(res.distance), (12, 12))
        self.assertEqual(shape(res.zdepth), (12, 12))
        self.assertEqual(shape(res.rgb), (12, 12, 3))
        d = flat(cam.rays()[1])
        z, dist, op = flat(res.zdepth), flat(res.distance), flat(res.opacity)
        self.assertEqual(op, flat(raw.opacity))
        for k, (t, a) in enumerate(zip(flat(raw.depth), op)):
            want = t / a if a > 0 else 0.0
            self.assertAlmostEqual(z[k], want, delta=1e-5 * abs(want) + 1e-7)
            length = math.sqrt(sum(v * v for v in d[3 * k:3 * k + 3]))
            self.assertAlmostEqual(dist[k], z[k] * length,
                                   delta=1e-5 * dist[k] + 1e-7)
        only = self.renderer.render_depth(cam, rgb=False, distance=False,
                                          opacity=False)
        self.assertIsNone(only.rgb)
        self.assertEqual(flat(only.zdepth), z)
        with self.assertRaises(ValueError):
            self.renderer.render_depth(cam, rgb=False, distance=False,
                                       zdepth=False, opacity=False)

    def test_arrays_are_the_buffers_c_wrote(self):
        # The arrays handed back are those whose memory the C call got:
        # record the pointers passed and compare with the arrays' data.
        if not nerf.HAVE_NUMPY:
            self.skipTest("without NumPy the outputs are memoryviews")
        import numpy as np
        api = nerf.render.lib
        real = api.nerf_renderer_render_depth
        passed = []

        def spy(*args):
            passed.append([ctypes.cast(a, ctypes.c_void_p).value
                           if a is not None else None for a in args[2:6]])
            return real(*args)

        api.nerf_renderer_render_depth = spy
        try:
            res = self.renderer.render_depth(camera())
        finally:
            api.nerf_renderer_render_depth = real
        self.assertEqual(len(passed), 1)
        for arr, addr in zip(res, passed[0]):
            self.assertIsInstance(arr, np.ndarray)
            self.assertEqual(arr.dtype, np.float32)
            self.assertEqual(arr.__array_interface__["data"][0], addr)
            self.assertTrue(arr.flags.owndata and arr.flags.c_contiguous)


class Npy(TestCase):
    def test_write_npy(self):
        path = os.path.join(_support.tmpdir(), "a.npy")
        nerf.write_npy(path, [[1.5, -2.0, 0.25], [3.0, 4.0, 5.0]])
        with open(path, "rb") as f:
            blob = f.read()
        self.assertEqual(blob[:8], b"\x93NUMPY\x01\x00")
        self.assertIn(b"'shape': (2, 3)", blob[:128])
        self.assertEqual(struct.unpack("<6f", blob[128:]),
                         (1.5, -2.0, 0.25, 3.0, 4.0, 5.0))
        if nerf.HAVE_NUMPY:
            import numpy as np
            self.assertEqual(np.load(path).tolist(),
                             [[1.5, -2.0, 0.25], [3.0, 4.0, 5.0]])
        nerf.write_npy(path, [1.0] * 6, shape=(1, 2, 3))
        with open(path, "rb") as f:
            self.assertIn(b"'shape': (1, 2, 3)", f.read(128))
        with self.assertRaises(ValueError):
            nerf.write_npy(path, [1.0] * 6, shape=(4,))
        with self.assertNerfError(nerf.NerfIOError, nerf.EIO,
                                  "/nonexistent-dir/a.npy"):
            nerf.write_npy("/nonexistent-dir/a.npy", [1.0])


class Points(TestCase):
    @classmethod
    def setUpClass(cls):
        cls.model = nerf.Model(preset="tiny", seed=7)
        cls.renderer = nerf.Renderer(
            cls.model, nerf.Sampler(preset="tiny", n_coarse=8, n_fine=8))
        cls.cams = [camera(), nerf.Camera.from_fov(10, 8, 50.0,
                                                   eye=(3.0, 1.0, 2.0))]

    def test_points_cap_normals_and_files(self):
        pts = self.renderer.points(self.cams, opacity_threshold=0.0)
        n = len(pts)
        ops = []
        for cam in self.cams:
            ops += flat(self.renderer.render_depth(cam).opacity)
        self.assertEqual(n, sum(1 for a in ops if a > 0))
        self.assertEqual(shape(pts.positions), (n, 3))
        self.assertEqual(shape(pts.colours), (n, 3))
        normals = flat(pts.normals)
        with_normal = 0
        for i in range(n):
            length = math.sqrt(sum(v * v for v in normals[3 * i:3 * i + 3]))
            self.assertTrue(length == 0.0 or abs(length - 1.0) < 1e-5)
            with_normal += length > 0
        self.assertGreater(with_normal, 0)

        capped = self.renderer.points(self.cams, opacity_threshold=0.0,
                                      max_points=10, stride=2)
        self.assertEqual(len(capped), 10)
        path = os.path.join(_support.tmpdir(), "cloud.ply")
        for ascii_ in (False, True):
            capped.write(path, ascii=ascii_)
            count, rows = read_ply(path)
            self.assertEqual(count, 10)
            self.assertAllClose(rows, capped.positions, 1e-6)
        with self.assertNerfError(nerf.NerfIOError, nerf.EIO,
                                  "/nonexistent-dir/x.ply"):
            capped.write("/nonexistent-dir/x.ply")
        capped.close()
        self.assertEqual(len(capped.positions), 10)  # copies outlive it

    def test_progress_cancel_and_bad_arguments(self):
        seen = []
        self.renderer.points(self.cams, progress=lambda p: seen.append(
            (p.done, p.total)))
        self.assertTrue(seen)
        self.assertEqual(seen[-1][0], seen[-1][1])
        self.assertEqual(seen[-1][1], 12 * 12 + 10 * 8)
        with self.assertRaises(nerf.NerfCancelled):
            self.renderer.points(self.cams, progress=lambda p: True)
        for kw in (dict(stride=0), dict(opacity_threshold=1.5),
                   dict(max_points=0)):
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "nerf_points_options"):
                self.renderer.points(self.cams, **kw)
        with self.assertRaises(ValueError):
            self.renderer.points([])


if __name__ == "__main__":
    _support.main()
