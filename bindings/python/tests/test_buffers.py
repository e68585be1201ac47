"""Array passing with NumPy (zero copy) and without (buffer protocol).

meson runs this script twice: as is, and with NERF_PY_NO_NUMPY=1.
"""

import array
import ctypes
import subprocess
import sys

import _support
from _support import TestCase, flat, nerf, shape

from nerf import _buffers

POS = [[0.1, 0.2, 0.3], [-0.4, 0.5, -0.6]]
DIRS = [[0.0, 0.0, 1.0], [0.6, 0.8, 0.0]]


class Mode(TestCase):
    def test_mode_follows_environment(self):
        self.assertEqual(nerf.HAVE_NUMPY, _support.expect_numpy_mode())

    def test_switch_is_honoured_in_a_fresh_process(self):
        import os
        env = dict(os.environ, NERF_PY_NO_NUMPY="1")
        out = subprocess.run(
            [sys.executable, "-c",
             "import nerf, sys; print(nerf.HAVE_NUMPY, "
             "'numpy' in sys.modules)"],
            env=env, capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertEqual(out.stdout.split(), ["False", "False"])


class BufferInputs(TestCase):
    """Inputs every installation accepts."""

    def test_array_f_is_not_copied(self):
        a = array.array("f", [1.0, 2.0, 3.0])
        buf = _buffers.as_float_input(a)
        self.assertFalse(buf.copied)
        self.assertEqual(ctypes.addressof(buf.ptr.contents),
                         a.buffer_info()[0])
        self.assertEqual(buf.size, 3)

    def test_bytearray_is_raw_float32(self):
        raw = bytearray(array.array("f", [0.5, 1.5]).tobytes())
        buf = _buffers.as_float_input(raw)
        self.assertFalse(buf.copied)
        self.assertEqual([buf.ptr[0], buf.ptr[1]], [0.5, 1.5])
        with self.assertRaises(ValueError):
            _buffers.as_float_input(bytearray(3))

    def test_readonly_and_converted_buffers_are_copied(self):
        ro = bytes(array.array("f", [0.25, 0.75]).tobytes())
        buf = _buffers.as_float_input(ro)
        self.assertTrue(buf.copied)
        self.assertEqual(buf.ptr[1], 0.75)
        d = _buffers.as_float_input(array.array("d", [1.0, 2.0]))
        self.assertTrue(d.copied)
        self.assertEqual([d.ptr[0], d.ptr[1]], [1.0, 2.0])
        i = _buffers.as_float_input(memoryview(array.array("i", [4, 5])))
        self.assertEqual([i.ptr[0], i.ptr[1]], [4.0, 5.0])
        strided = memoryview(array.array("f", [1, 9, 2, 9]))[::2]
        s = _buffers.as_float_input(strided)
        self.assertTrue(s.copied)
        self.assertEqual([s.ptr[0], s.ptr[1]], [1.0, 2.0])
        with self.assertRaises(TypeError):
            _buffers.as_float_input(object())

    def test_memoryview_shape_is_kept(self):
        mv = memoryview(array.array("f", range(6))).cast("B").cast("f",
                                                                  (2, 3))
        buf = _buffers.as_float_input(mv)
        self.assertEqual(buf.shape, (2, 3))
        self.assertFalse(buf.copied)

    def test_every_input_kind_gives_the_same_query(self):
        with nerf.Model(preset="tiny", seed=3) as m:
            want = flat(m.query(POS, DIRS)[0])
            kinds = [
                (array.array("f", flat(POS)), array.array("f", flat(DIRS))),
                (memoryview(array.array("f", flat(POS))),
                 memoryview(array.array("f", flat(DIRS)))),
                (bytearray(array.array("f", flat(POS)).tobytes()),
                 bytes(array.array("f", flat(DIRS)).tobytes())),
                (array.array("d", flat(POS)), tuple(flat(DIRS))),
            ]
            for pos, dirs in kinds:
                self.assertEqual(flat(m.query(pos, dirs)[0]), want)


class Outputs(TestCase):
    def test_output_types(self):
        with nerf.Model(preset="tiny") as m:
            rgb, sigma = m.query(POS, DIRS)
        if nerf.HAVE_NUMPY:
            import numpy as np
            self.assertIsInstance(rgb, np.ndarray)
            self.assertEqual(rgb.dtype, np.float32)
            self.assertTrue(rgb.flags.c_contiguous)
        else:
            self.assertIsInstance(rgb, memoryview)
            self.assertEqual(rgb.format, "f")
            self.assertIsInstance(rgb.obj, array.array)
            self.assertFalse(rgb.readonly)
        self.assertEqual(shape(rgb), (2, 3))
        self.assertEqual(shape(sigma), (2,))

    def test_uint8_output(self):
        m = nerf.Model(preset="tiny")
        r = nerf.Renderer(m, nerf.Sampler(n_coarse=4, n_fine=4))
        cam = nerf.Camera.from_fov(4, 4, 40.0, eye=(0, -4, 0))
        rgb = r.render_image_u8(cam).rgb
        self.assertEqual(shape(rgb), (4, 4, 3))
        if nerf.HAVE_NUMPY:
            self.assertEqual(str(rgb.dtype), "uint8")
        else:
            self.assertEqual(rgb.format, "B")
        r.close()
        m.close()


class NumpyInputs(TestCase):
    def setUp(self):
        if not nerf.HAVE_NUMPY:
            self.skipTest("NumPy disabled or absent")
        import numpy
        self.np = numpy

    def test_float32_contiguous_is_not_copied(self):
        np = self.np
        a = np.arange(12, dtype=np.float32).reshape(4, 3)
        buf = _buffers.as_float_input(a)
        self.assertFalse(buf.copied)
        self.assertEqual(ctypes.addressof(buf.ptr.contents),
                         a.ctypes.data)
        self.assertEqual(buf.shape, (4, 3))

    def test_other_arrays_are_converted(self):
        np = self.np
        for a in (np.arange(12, dtype=np.float64).reshape(4, 3),
                  np.arange(24, dtype=np.float32).reshape(4, 6)[:, ::2],
                  np.asfortranarray(np.ones((3, 3), np.float32)),
                  np.arange(6, dtype=np.int32),
                  np.frombuffer(bytes(13), np.float32, 3, offset=1),
                  np.arange(4, dtype=">f4")):
            buf = _buffers.as_float_input(a)
            self.assertTrue(buf.copied)
            got = [buf.ptr[i] for i in range(buf.size)]
            self.assertEqual(got, [float(v) for v in a.ravel(order="C")])

    def test_numpy_query_and_image_metrics(self):
        np = self.np
        with nerf.Model(preset="tiny", seed=3) as m:
            rgb, _ = m.query(np.array(POS, np.float32),
                             np.array(DIRS, np.float64))
            self.assertEqual(flat(rgb), flat(m.query(POS, DIRS)[0]))
        img = np.full((12, 12, 3), 0.5, np.float32)
        self.assertEqual(nerf.ssim(img, img), 1.0)
        self.assertAlmostEqual(nerf.psnr(img, img + 0.1), 20.0, places=3)


if __name__ == "__main__":
    _support.main()
