"""Bad arguments are refused in Python, before anything reaches C (issue
53): paths with a NUL, integers a C field cannot hold, arrays of another
shape, ragged sequences, NaN where the library refuses it, and cameras
whose render would allocate before the library checked them.

meson runs this script twice: as is, and with NERF_PY_NO_NUMPY=1.
"""

import array
import ctypes
import os

import _support
from _support import TestCase, nerf

from nerf import _buffers, render, structs


def camera(size=4):
    return nerf.Camera.from_fov(size, size, 40.0, eye=(0.0, -4.0, 1.0))


class Paths(TestCase):
    """Every function taking a path goes through one converter."""

    @classmethod
    def setUpClass(cls):
        cls.dir = _support.tmpdir()
        cls.model_path = os.path.join(cls.dir, "args-model.nerf")
        with nerf.Model(preset="tiny") as m:
            m.save(cls.model_path)

    def calls(self, path):
        """Each path-taking call of the binding, given path."""
        model = nerf.Model(preset="tiny")
        image = [[[0.5, 0.5, 0.5]] * 2] * 2
        return {
            "Model.load": lambda: nerf.Model.load(path),
            "Model.import_npz": lambda: nerf.Model.import_npz(path),
            "Model.save": lambda: model.save(path),
            "Model.export": lambda: model.export(path),
            "Model.write_density_grid":
                lambda: model.write_density_grid(path, resolution=4),
            "Dataset": lambda: nerf.Dataset(path),
            "load_camera_path": lambda: nerf.load_camera_path(path),
            "write_scene": lambda: nerf.write_scene(path, width=8, height=8),
            "read_png": lambda: nerf.read_png(path),
            "read_image": lambda: nerf.read_image(path),
            "write_png": lambda: nerf.write_png(path, image),
            "write_png8": lambda: nerf.write_png(path, bytes(12), 2, 2, 3),
            "write_npy": lambda: nerf.write_npy(path, [1.0, 2.0]),
            "TrainerOptions":
                lambda: nerf.TrainerOptions(checkpoint_path=path),
        }

    def test_embedded_nul_is_refused(self):
        # Before: C read the path up to the NUL, so Model.load(p + "\0junk")
        # loaded p and Model.save(p + "\0junk") wrote p.
        target = self.model_path + "\0junk"
        before = os.stat(self.model_path).st_mtime_ns
        for name, call in self.calls(target).items():
            with self.subTest(name):
                with self.assertRaises(ValueError) as cm:
                    call()
                self.assertIn("embedded null character", str(cm.exception))
        self.assertEqual(os.stat(self.model_path).st_mtime_ns, before)
        self.assertEqual(os.listdir(self.dir).count("args-model.nerf"), 1)

    def test_bytes_nul_and_pathlike(self):
        with self.assertRaises(ValueError):
            nerf.Model.load(os.fsencode(self.model_path) + b"\0")
        import pathlib
        nerf.Model.load(pathlib.Path(self.model_path)).close()
        nerf.Model.load(os.fsencode(self.model_path)).close()

    def test_not_a_path_is_a_type_error(self):
        for name, call in self.calls(3).items():
            with self.subTest(name):
                with self.assertRaises(TypeError) as cm:
                    call()
                self.assertIn("not int", str(cm.exception))

    def test_struct_path_field(self):
        opts = nerf.TrainerOptions()
        with self.assertRaises(ValueError):
            opts.checkpoint_path = "a\0b"
        with self.assertRaises(TypeError):
            opts.checkpoint_path = 7
        opts.checkpoint_path = "ok.nerf"
        self.assertEqual(opts.to_dict()["checkpoint_path"], "ok.nerf")


class Fields(TestCase):
    """ctypes wraps silently; every integer field refuses instead."""

    def integer_fields(self):
        for cls in structs.ALL_STRUCTS:
            for name, ctype, *_ in cls._fields_:
                if ctype in (ctypes.c_uint32, ctypes.c_int32, ctypes.c_uint64,
                             ctypes.c_int):
                    yield cls, name, ctype

    def test_every_integer_field_is_checked(self):
        seen = 0
        for cls, name, ctype in self.integer_fields():
            bits = 8 * ctypes.sizeof(ctype)
            signed = ctype(-1).value < 0
            lo = -(1 << (bits - 1)) if signed else 0
            hi = (1 << (bits - 1)) - 1 if signed else (1 << bits) - 1
            s = cls.__new__(cls)   # no *_init call: only the field matters
            with self.subTest("%s.%s" % (cls.__name__, name)):
                setattr(s, name, hi)
                self.assertEqual(int(getattr(s, name)), hi)
                for bad in (lo - 1, hi + 1):
                    with self.assertRaises(ValueError) as cm:
                        setattr(s, name, bad)
                    self.assertIn("%s.%s" % (cls.__name__, name),
                                  str(cm.exception))
                named = isinstance(cls.__dict__[name], structs._NamedField)
                # A named field takes a str as the name of its value.
                for bad in (1.5, None) + (() if named else ("3",)):
                    with self.assertRaises(TypeError):
                        setattr(s, name, bad)
                self.assertEqual(int(getattr(s, name)), hi)
            seen += 1
        self.assertGreater(seen, 60)

    def test_camera_width_minus_one(self):
        # Before: width 4294967295.
        with self.assertRaises(ValueError) as cm:
            nerf.Camera(width=-1)
        self.assertIn("Camera.width: -1", str(cm.exception))
        cam = camera()
        with self.assertRaises(ValueError):
            cam.height = -1
        self.assertEqual(cam.height, 4)
        with self.assertRaises(TypeError):
            nerf.Camera(width=16.0)

    def test_options_structs_too(self):
        with self.assertRaises(ValueError):
            nerf.RendererOptions(threads=-1)
        with self.assertRaises(ValueError):
            nerf.Sampler(n_coarse=-8)
        with self.assertRaises(ValueError):
            nerf.Model(preset="tiny", seed=-1)
        with self.assertRaises(ValueError):
            nerf.SceneOptions(n_train=1 << 32)
        with self.assertRaises(TypeError):
            nerf.MeshOptions(resolution=64.5)
        # Named fields: a name, or an int the field can hold.
        with self.assertRaises(ValueError):
            nerf.ModelOptions(encoding=-2)
        with self.assertRaises(TypeError):
            nerf.ModelOptions(matmul=1.0)
        self.assertEqual(nerf.ModelOptions(space="ndc").space,
                         nerf.SPACE_NDC)

    def test_size_arguments(self):
        with nerf.Sampler(n_coarse=4, n_fine=0) as s:
            with self.assertRaises(ValueError):
                s.sample_coarse(-1)
            with self.assertRaises(TypeError):
                s.sample_coarse(2.5)
            with self.assertRaises(ValueError):
                s.sample_coarse(1, first_ray=-1)
        ds, model, sampler = _support.tiny_setup()
        with nerf.Trainer(model, ds, sampler, batch_rays=16) as t:
            # Before: -1 became 2^64 - 1 steps.
            with self.assertRaises(ValueError):
                t.run(-1)
            with self.assertRaises(TypeError):
                t.run(2.0)
        with self.assertRaises(TypeError):
            ds.camera(0.5)
        with self.assertRaises(TypeError):
            ds.spiral_camera(1.0)
        with self.assertRaises(ValueError):
            ds.spiral_camera(-1)
        ds.close()
        cam = camera()
        with self.assertRaises(ValueError):
            cam.rays(first=-1)
        with self.assertRaises(TypeError):
            cam.rays(count=2.0)


class Shapes(TestCase):
    def test_pose(self):
        cam = camera()
        before = cam.pose
        # Before: a 4 x 3 matrix (12 numbers) was taken as 3 x 4.
        with self.assertRaises(ValueError) as cm:
            cam.pose = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]]
        self.assertIn("expected shape (3, 4) or (4, 4), got (4, 3)",
                      str(cm.exception))
        with self.assertRaises(ValueError) as cm:
            cam.pose = [[1, 0, 0, 0], [0, 1, 0], [0, 0, 1, 0, 5]]
        self.assertIn("ragged", str(cm.exception))
        with self.assertRaises(ValueError):
            cam.pose = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0],
                        [0, 0, 1, 1]]
        with self.assertRaises(ValueError):
            cam.update(c2w=[0.0] * 13)
        with self.assertRaises(TypeError):
            cam.pose = [["1", 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "pose"):
            cam.pose = [[1, 0, 0, 0], [0, 1, 0, 0],
                        [0, 0, 1, float("nan")]]
        self.assertEqual(cam.pose, before)
        # What stays accepted: 3 x 4, 4 x 4 ending 0 0 0 1, 12 flat.
        cam.pose = [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3]]
        cam.pose = [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]
        cam.update(c2w=[1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3])
        self.assertEqual(cam.pose[2], [0.0, 0.0, 1.0, 3.0])

    def test_query(self):
        pos = [[0.1, 0.2, 0.3]] * 4
        with nerf.Model(preset="tiny") as m:
            # Before: directions of shape (3, 4) were read as 4 x 3.
            with self.assertRaises(ValueError) as cm:
                m.query(pos, [[0.0, 0.0, 1.0, 0.0]] * 3)
            self.assertIn("directions: expected shape (4, 3), got (3, 4)",
                          str(cm.exception))
            with self.assertRaises(ValueError):
                m.query([[0.1, 0.2, 0.3], [0.1, 0.2]])
            with self.assertRaises(ValueError):
                m.query([[[0.1, 0.2, 0.3]]])
            with self.assertRaises(ValueError):
                m.query([0.1, 0.2, 0.3, 0.4])
            with self.assertRaises(TypeError):
                m.query([[0.1, "0.2", 0.3]])
            with self.assertRaises(TypeError):
                m.query(pos, "directions")
            # Flat rows stay accepted: a 1-D input holds whole rows.
            rgb, _ = m.query(array.array("f", [0.1, 0.2, 0.3] * 2),
                             [0.0, 0.0, 1.0] * 2)
            self.assertEqual(tuple(rgb.shape), (2, 3))

    def test_numpy_shapes_and_dtypes(self):
        if not nerf.HAVE_NUMPY:
            self.skipTest("NumPy disabled or absent")
        import numpy as np
        with nerf.Model(preset="tiny") as m:
            with self.assertRaises(ValueError):
                m.query(np.zeros((4, 3)), np.zeros((3, 4)))
            with self.assertRaises(ValueError):
                m.query(np.zeros((2, 3, 1)))
            for bad in (np.array(["a", "b", "c"]),
                        np.zeros(3, dtype=complex),
                        np.array([object(), 1, 2], dtype=object)):
                with self.assertRaises(TypeError):
                    m.query(bad)
        cam = camera()
        with self.assertRaises(ValueError):
            cam.pose = np.eye(4)[:, :3]
        cam.pose = np.eye(4)

    def test_rays_and_samplers(self):
        m = nerf.Model(preset="tiny")
        s = nerf.Sampler(n_coarse=4, n_fine=4)
        with nerf.Renderer(m, s) as r:
            o = [[0.0, -4.0, 0.0]] * 3
            with self.assertRaises(ValueError):
                r.render_rays(o, [[0.0, 1.0, 0.0, 0.0]] * 3)
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "directions: value 4 of 9 is inf"):
                r.render_rays(o, [[0.0, 1.0, 0.0], [0.0, float("inf"), 0.0],
                                  [0.0, 1.0, 0.0]])
        t = s.sample_coarse(2)
        w = [[0.25] * 4] * 2
        with self.assertRaises(ValueError):
            s.sample_fine(t, [[0.25] * 2] * 4)
        with self.assertRaises(ValueError):
            s.sample_fine([[2.0, 3.0, 4.0]] * 2, w)
        with self.assertRaises(ValueError):
            s.sample_fine(t, w, training=True, u=[[0.5] * 2] * 4)
        with self.assertRaises(ValueError):
            s.sample_coarse(2, training=True, u=[[0.5] * 2] * 4)
        self.assertEqual(tuple(s.sample_fine(t, w).shape), (2, 8))

    def test_images_and_metrics(self):
        path = os.path.join(_support.tmpdir(), "args.png")
        img = [[[0.5] * 3] * 4] * 2          # 2 x 4 x 3
        with self.assertRaises(ValueError):
            nerf.write_png(path, img, width=2, height=4)
        with self.assertRaises(ValueError):
            nerf.write_png(path, img, channels=4)
        with self.assertRaises(ValueError):
            nerf.write_png(path, [0.5] * 24)          # flat: size needed
        nerf.write_png(path, [0.5] * 24, width=4, height=2)
        with self.assertRaises(ValueError):
            nerf.write_png(path, bytearray(24), width=3, height=3)
        nerf.write_png(path, bytearray(24), width=4, height=2, channels=3)
        self.assertEqual(tuple(nerf.read_png(path).shape), (2, 4, 4))
        with self.assertRaises(ValueError):
            nerf.psnr([[0.5, 0.5, 0.5]], [[0.5], [0.5], [0.5]])
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "psnr: b"):
            nerf.psnr([0.5, 0.5], [0.5, float("nan")])
        with self.assertRaises(ValueError):
            nerf.write_npy(os.path.join(_support.tmpdir(), "a.npy"),
                           [[1.0, 2.0, 3.0]] * 2, shape=(3, 2))
        with self.assertRaises(ValueError):
            nerf.MeshOptions(box=(0, 0, 0, 1, 1))
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "box"):
            nerf.MeshOptions(box=(0, 0, 0, 1, 1, float("inf")))


class Cameras(TestCase):
    """A render's outputs are sized by its camera: the camera is checked
    (by the library's own check) before they are allocated."""

    def setUp(self):
        self.model = nerf.Model(preset="tiny")
        self.renderer = nerf.Renderer(self.model,
                                      nerf.Sampler(n_coarse=4, n_fine=0))
        self.allocated = []
        real_f, real_u8 = _buffers.FloatOutput, _buffers.Uint8Output

        def spy(real):
            def make(shape, *args):
                self.allocated.append(tuple(shape))
                return real(shape, *args)
            return make

        render._buffers.FloatOutput = spy(real_f)
        render._buffers.Uint8Output = spy(real_u8)
        self.addCleanup(setattr, _buffers, "FloatOutput", real_f)
        self.addCleanup(setattr, _buffers, "Uint8Output", real_u8)
        self.addCleanup(self.renderer.close)
        self.addCleanup(self.model.close)

    def test_refused_before_allocation(self):
        huge = camera()
        # In range for the uint32 field, not for a camera: before, this
        # asked NumPy for 4294967295 x 8 pixels (384 GiB) first.
        huge.width = 4294967295
        huge.height = 8
        bad_focal = camera()
        bad_focal.fx = 0.0
        r = self.renderer
        calls = {
            "render_image": lambda cam: r.render_image(cam),
            "render_image_u8": lambda cam: r.render_image_u8(cam, depth=True),
            "render_depth": lambda cam: r.render_depth(cam),
            "points": lambda cam: r.points([camera(), cam]),
            "rays": lambda cam: cam.rays(),
        }
        for name, call in calls.items():
            for cam, what in ((huge, "4294967295 x 8"),
                              (bad_focal, "fx and fy")):
                with self.subTest(name=name, camera=what):
                    with self.assertNerfError(nerf.NerfInvalidArgument,
                                              nerf.EINVAL, what):
                        call(cam)
        self.assertEqual(self.allocated, [])
        with self.assertRaises(TypeError):
            r.render_image("camera")
        self.assertEqual(self.allocated, [])

    def test_a_valid_camera_renders(self):
        out = self.renderer.render_image(camera(4))
        self.assertEqual(tuple(out.rgb.shape), (4, 4, 3))
        self.assertEqual(self.allocated, [(4, 4, 3), (4, 4), (4, 4)])

    def test_failed_allocation_says_the_size(self):
        # Not a real 48 GiB request: an ASan build would abort on it.
        def fail():
            raise MemoryError()

        with self.assertRaises(MemoryError) as cm:
            _buffers._allocate(fail, (65536, 65536, 3), 4,
                               "render_image: rgb")
        self.assertIn("render_image: rgb: cannot allocate 48.0 GiB for an "
                      "array of shape (65536, 65536, 3)", str(cm.exception))


if __name__ == "__main__":
    _support.main()
