"""Cameras, samplers, renderers and progress callbacks."""

import os
import signal
import struct
import threading

import _support
from _support import TestCase, flat, nerf, shape


def f32(x):
    """x rounded to the nearest float32, as C's float arithmetic rounds."""
    return struct.unpack("f", struct.pack("f", x))[0]


def to_byte(c):
    """The library's 8-bit value of colour c, in its float32 arithmetic:
    (uint8_t)(c * 255.0f + 0.5f), 0 below 0 and 255 from 1.  Python's
    round(255 * c) in double, halves to even, differs from it where 255 c
    falls within a float rounding of a half, which some renders hit."""
    if not c > 0.0:
        return 0
    if c >= 1.0:
        return 255
    return int(f32(f32(255.0 * c) + 0.5))


class Boom(Exception):
    """Raised by test callbacks."""


def camera(size=8):
    return nerf.Camera.from_fov(size, size, 40.0, eye=(0.0, -4.0, 1.0))


class Cameras(TestCase):
    def test_defaults_come_from_the_library(self):
        cam = nerf.Camera()
        self.assertEqual(cam.struct_size, 100)
        self.assertEqual(cam.pose, [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]])
        self.assertEqual((cam.width, cam.fx), (0, 0.0))
        self.assertEqual((cam.k1, cam.k2, cam.p1, cam.p2, cam.k3),
                         (0.0, 0.0, 0.0, 0.0, 0.0))

    def test_lens(self):
        # A lens bends the rays of off-centre pixels, not the centre's.
        cam = camera(9)
        d = flat(cam.rays()[1])
        cam.k1 = -0.3
        d2 = flat(cam.rays()[1])
        centre = 3 * (4 * 9 + 4)
        self.assertEqual(d[centre:centre + 3], d2[centre:centre + 3])
        self.assertNotEqual(d[0:3], d2[0:3])
        cam.k1 = float("nan")
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            cam.rays()

    def test_from_fov_and_look_at(self):
        cam = nerf.Camera.from_fov(20, 10, 90.0)
        self.assertAlmostEqual(cam.fx, 10.0, places=4)
        self.assertEqual((cam.cx, cam.cy), (10.0, 5.0))
        cam.look_at((0, -4, 0), (0, 0, 0), (0, 0, 1))
        pose = cam.pose
        # The camera's back axis (third column) points away from the target.
        self.assertAllClose([r[2] for r in pose], [0, -1, 0], 1e-6)
        self.assertAllClose([r[3] for r in pose], [0, -4, 0], 1e-6)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            cam.look_at((1, 1, 1), (1, 1, 1))
        with self.assertRaises(ValueError):
            cam.look_at((1, 1), (0, 0, 0))
        with self.assertRaises(ValueError):
            nerf.Camera.from_fov(4, 4, 200.0)

    def test_pose_and_copy(self):
        cam = nerf.Camera(width=4, height=4, fx=4, fy=4, cx=2, cy=2)
        cam.pose = [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]
        other = cam.copy()
        other.pose = list(range(12))
        self.assertEqual(cam.pose[2], [0, 0, 1, 3])
        self.assertEqual(other.c2w[11], 11.0)
        self.assertEqual(nerf.Camera(c2w=list(range(12))).c2w[5], 5.0)
        with self.assertRaises(ValueError):
            cam.pose = [1, 2, 3]
        self.assertEqual(cam.pixel_count, 16)

    def test_rays(self):
        cam = nerf.Camera.from_fov(4, 4, 60.0, eye=(0, -4, 0))
        origins, dirs = cam.rays()
        self.assertEqual(shape(origins), (16, 3))
        self.assertEqual(shape(dirs), (16, 3))
        self.assertAllClose(flat(origins)[:3], [0, -4, 0], 1e-6)
        # Pixels 5 and 10 straddle the centre: their mean points at +y.
        d = flat(dirs)
        mean = [(d[15 + k] + d[30 + k]) / 2 for k in range(3)]
        self.assertAllClose(mean, [0, 1, 0], 1e-5)
        part_o, part_d = cam.rays(first=14)
        self.assertEqual(shape(part_d), (2, 3))
        self.assertAllClose(part_d, d[42:], 1e-6)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            cam.rays(first=10, count=10)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.Camera().rays(count=1)   # no intrinsics


class Samplers(TestCase):
    def test_options(self):
        s = nerf.Sampler(preset="tiny", seed=2, t_near=1.0, t_far=3.0)
        self.assertEqual((s.n_coarse, s.n_fine), (32, 64))
        self.assertEqual(s.options.seed, 2)
        self.assertEqual(nerf.Sampler().n_coarse, 64)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.Sampler(t_near=3.0, t_far=2.0)
        with self.assertRaises(TypeError):
            nerf.Sampler(reserved0=1)
        s.close()

    def test_sampling(self):
        s = nerf.Sampler(n_coarse=4, n_fine=3, t_near=2.0, t_far=6.0)
        t = s.sample_coarse(2)
        self.assertEqual(shape(t), (2, 4))
        self.assertAllClose(t, [2, 10 / 3, 14 / 3, 6] * 2, 1e-5)
        jittered = s.sample_coarse(2, training=True, first_ray=5)
        self.assertNotEqual(flat(jittered), flat(t))
        again = s.sample_coarse(1, training=True, first_ray=6)
        self.assertEqual(flat(again), flat(jittered)[4:])
        u = [0.5] * 8
        self.assertEqual(flat(s.sample_coarse(2, True, u=u)),
                         flat(s.sample_coarse(2, True, u=u)))
        with self.assertRaises(ValueError):
            s.sample_coarse(2, True, u=[0.5])
        w = [0.0, 1.0, 0.0, 0.0] * 2
        fine = s.sample_fine(t, w)
        self.assertEqual(shape(fine), (2, 7))
        f = flat(fine)
        self.assertEqual(f[:7], sorted(f[:7]))
        fine_u = s.sample_fine(t, w, training=True, u=[0.1, 0.5, 0.9] * 2)
        self.assertEqual(shape(fine_u), (2, 7))
        with self.assertRaises(ValueError):
            s.sample_fine(t, w[:4])
        coarse_only = nerf.Sampler(n_coarse=4, n_fine=0)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            coarse_only.sample_fine(t, w)


class Rendering(TestCase):
    @classmethod
    def setUpClass(cls):
        cls.model = nerf.Model(preset="tiny", seed=5)
        cls.sampler = nerf.Sampler(n_coarse=8, n_fine=8, seed=5)

    @classmethod
    def tearDownClass(cls):
        cls.model.close()
        cls.sampler.close()

    def renderer(self, **kw):
        kw.setdefault("chunk_rays", 64)
        return nerf.Renderer(self.model, self.sampler, **kw)

    def test_render_image(self):
        with self.renderer(white_background=1) as r:
            out = r.render_image(camera())
            self.assertEqual(shape(out.rgb), (8, 8, 3))
            self.assertEqual(shape(out.depth), (8, 8))
            self.assertEqual(shape(out.opacity), (8, 8))
            # sum(w) may exceed 1 by float rounding (1.0000002 seen).
            self.assertTrue(all(0 <= v <= 1 + 1e-5 for v in flat(out.opacity)))
            only = r.render_image(camera(), depth=False, opacity=False)
            self.assertIsNone(only.depth)
            self.assertEqual(flat(only.rgb), flat(out.rgb))
            u8 = r.render_image_u8(camera(), depth=True, opacity=True)
            self.assertEqual(shape(u8.rgb), (8, 8, 3))
            want = [to_byte(v) for v in flat(out.rgb)]
            self.assertEqual([int(v) for v in flat(u8.rgb)], want)
            self.assertEqual(flat(u8.depth), flat(out.depth))
            with self.assertRaises(ValueError):
                r.render_image(camera(), rgb=False, depth=False, opacity=False)
            with self.assertRaises(TypeError):
                r.render_image("camera")

    def test_render_rays_match_image(self):
        with self.renderer() as r:
            cam = camera()
            image = r.render_image(cam)
            o, d = cam.rays()
            rays = r.render_rays(o, d)
            self.assertEqual(shape(rays.rgb), (64, 3))
            self.assertEqual(shape(rays.depth), (64,))
            self.assertAllClose(rays.rgb, image.rgb, 1e-5)
            self.assertAllClose(rays.opacity, image.opacity, 1e-5)
            part = r.render_rays(flat(o)[:6], flat(d)[:6], rgb=False,
                                 depth=False)
            self.assertEqual(shape(part.opacity), (2,))
            with self.assertRaises(ValueError):
                r.render_rays(o, flat(d)[:3])
            with self.assertRaises(ValueError):
                r.render_rays(o, d, rgb=False, depth=False, opacity=False)

    def test_errors(self):
        bad = nerf.Camera(width=4, height=4)   # no focal length
        with self.renderer() as r:
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
                r.render_image(bad)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            self.renderer(chunk_rays=0)
        with self.assertRaises(TypeError):
            nerf.Renderer(self.sampler, self.model)


class Callbacks(TestCase):
    @classmethod
    def setUpClass(cls):
        cls.model = nerf.Model(preset="tiny", seed=6)
        cls.sampler = nerf.Sampler(n_coarse=8, n_fine=8)

    def renderer(self, **kw):
        return nerf.Renderer(self.model, self.sampler, chunk_rays=64,
                             threads=1, **kw)

    def test_progress(self):
        seen = []
        with self.renderer(progress=seen.append) as r:
            r.render_image(camera(16))
            self.assertTrue(seen)
            self.assertTrue(all(p.kind == "render" for p in seen))
            self.assertEqual(seen[-1].done, 256)
            self.assertEqual(seen[-1].total, 256)
            self.assertEqual([p.done for p in seen],
                             sorted(p.done for p in seen))
            self.assertEqual(seen[-1].fraction, 1.0)
            # A per-call callback replaces the default for that call only.
            mine = []
            r.render_image(camera(16), progress=mine.append)
            self.assertTrue(mine)
            n = len(seen)
            r.progress = None
            r.render_image(camera(16))
            self.assertEqual(len(seen), n)
            with self.assertRaises(TypeError):
                r.progress = 42

    def test_cancel_from_callback(self):
        calls = []

        def stop(p):
            calls.append(p.done)
            return True

        with self.renderer(progress=stop) as r:
            with self.assertNerfError(nerf.NerfCancelled, nerf.ECANCELLED):
                r.render_image(camera(16))
            self.assertEqual(len(calls), 1)
            # The renderer works again afterwards.
            r.progress = None
            self.assertEqual(shape(r.render_image(camera(16)).rgb),
                             (16, 16, 3))

    def test_cancel_method_in_callback(self):
        with self.renderer() as r:
            r.progress = lambda p: r.cancel()
            with self.assertRaises(nerf.NerfCancelled):
                r.render_rays(*camera(16).rays())
            r.progress = None

    def test_raising_callback_is_reraised(self):
        def bad(p):
            raise Boom("from the callback")

        with self.renderer(progress=bad) as r:
            with self.assertRaises(Boom) as cm:
                r.render_image(camera(16))
            self.assertEqual(str(cm.exception), "from the callback")
            self.assertNotIsInstance(cm.exception, nerf.NerfError)
            with self.assertRaises(KeyboardInterrupt):
                r.render_image(camera(16), progress=self.interrupt)
            # Nothing is left pending for the next call.
            r.progress = None
            r.render_image(camera(16))

    def test_ctrl_c_cancels(self):
        calls = []

        def press_ctrl_c(p):
            calls.append(p.done)
            if len(calls) == 1:
                os.kill(os.getpid(), signal.SIGINT)

        with self.renderer(progress=press_ctrl_c) as r:
            with self.assertRaises(KeyboardInterrupt):
                r.render_image(camera(16))
            self.assertEqual(calls, [64])   # stopped at the next chunk
            self.assertIs(signal.getsignal(signal.SIGINT),
                          signal.default_int_handler)
            r.progress = None
            r.render_image(camera(4))       # nothing left pending

    def test_reentrant_call_is_refused(self):
        with self.renderer() as r:
            r.progress = lambda p: r.render_image(camera(4))
            with self.assertRaises(RuntimeError) as cm:
                r.render_image(camera(16))
            self.assertIn("busy", str(cm.exception))
            r.progress = None
            r.render_image(camera(4))

    @staticmethod
    def interrupt(p):
        raise KeyboardInterrupt

    def test_cancel_from_another_thread(self):
        started = threading.Event()
        release = threading.Event()

        def slow(p):
            started.set()
            release.wait(10)   # hold the render until cancel() arrived

        with self.renderer(progress=slow) as r:
            result = {}

            def run():
                try:
                    r.render_image(camera(16))
                    result["rc"] = "ok"
                except nerf.NerfCancelled:
                    result["rc"] = "cancelled"

            t = threading.Thread(target=run)
            t.start()
            self.assertTrue(started.wait(20))
            r.cancel()
            release.set()
            t.join(30)
            self.assertEqual(result.get("rc"), "cancelled")
        r.cancel()   # closed: a no-op


if __name__ == "__main__":
    _support.main()
