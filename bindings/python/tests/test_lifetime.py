"""Handles freed in every order: close(), del, garbage cycles, exit."""

import gc
import os
import subprocess
import sys
import textwrap
import weakref

import _support
from _support import TestCase, flat, nerf


def camera():
    return nerf.Camera.from_fov(8, 8, 40.0, eye=(0.0, -4.0, 1.0))


def small_renderer(model=None, sampler=None):
    model = model or nerf.Model(preset="tiny", seed=2)
    sampler = sampler or nerf.Sampler(n_coarse=4, n_fine=4)
    return nerf.Renderer(model, sampler, chunk_rays=64, threads=1)


def holder(*objs):
    """A progress callback that references ``objs``."""
    return lambda p: objs and None


class Order(TestCase):
    def test_model_deleted_before_renderer(self):
        model = nerf.Model(preset="tiny", seed=2)
        sampler = nerf.Sampler(n_coarse=4, n_fine=4)
        renderer = nerf.Renderer(model, sampler)
        res = model._res
        del model, sampler
        gc.collect()
        self.assertIsNotNone(res.ptr)   # still used by the renderer
        out = renderer.render_image(camera())
        self.assertTrue(_support.all_finite(out.rgb))
        del renderer
        gc.collect()
        self.assertIsNone(res.ptr)      # freed with its last dependent

    def test_close_defers_while_dependents_live(self):
        r = small_renderer()
        model, sampler = r.model, r.sampler
        model.close()
        model.close()                   # idempotent
        sampler.close()
        self.assertTrue(model.closed)
        with self.assertRaises(ValueError):
            model.step
        with self.assertRaises(ValueError):
            nerf.Renderer(model, nerf.Sampler())
        with self.assertRaises(ValueError):
            with model:
                pass
        self.assertIsNotNone(model._res.ptr)
        r.render_image(camera())        # the renderer still works
        r.close()
        self.assertIsNone(model._res.ptr)
        self.assertIsNone(sampler._res.ptr)
        self.assertIsNone(r._res.ptr)
        with self.assertRaises(ValueError):
            r.render_image(camera())
        self.assertIn("closed", repr(r))

    def test_two_renderers_share_a_model(self):
        model = nerf.Model(preset="tiny")
        a, b = small_renderer(model), small_renderer(model)
        model.close()
        a.close()
        self.assertIsNotNone(model._res.ptr)
        b.render_image(camera())
        b.close()
        self.assertIsNone(model._res.ptr)

    def test_reference_cycles_in_any_order(self):
        resources = []
        for flip in range(4):
            model = nerf.Model(preset="tiny")
            sampler = nerf.Sampler(n_coarse=4, n_fine=4)
            r = nerf.Renderer(model, sampler)
            # Cycles: the collector finalises their members in any order.
            model.partner = r
            sampler.partner = model if flip % 2 else r
            if flip >= 2:
                r.progress = holder(r, model)
            resources += [model._res, sampler._res, r._res]
            refs = [weakref.ref(x) for x in (model, sampler, r)]
            del model, sampler, r
            gc.collect()
            self.assertTrue(all(ref() is None for ref in refs))
        self.assertTrue(all(res.ptr is None for res in resources))

    def test_callback_holding_its_renderer(self):
        r = small_renderer()
        r.progress = holder(r)          # a cycle through the callback
        r.render_image(camera())
        ref = weakref.ref(r)
        res = r._res
        del r
        gc.collect()
        self.assertIsNone(ref())
        self.assertIsNone(res.ptr)

    def test_close_inside_own_callback(self):
        r = small_renderer()
        calls = []

        def close_me(p):
            calls.append(p.done)
            r.close()

        r.progress = close_me
        out = r.render_image(camera())   # the call in flight completes
        self.assertTrue(_support.all_finite(out.rgb))
        self.assertTrue(calls)
        self.assertIsNone(r._res.ptr)    # freed once the call returned

    def test_trainer_outlives_its_inputs(self):
        ds, model, sampler = _support.tiny_setup()
        t = nerf.Trainer(model, ds, sampler, batch_rays=16)
        deps = [ds._res, model._res, sampler._res]
        ds.close()
        del model, sampler, ds
        gc.collect()
        self.assertEqual(t.step().step, 1)
        self.assertEqual(t.model.step, 1)
        with self.assertRaises(ValueError):
            len(t.dataset)
        del t
        gc.collect()
        self.assertTrue(all(res.ptr is None for res in deps))

    def test_borrowed_image_keeps_dataset(self):
        ds = nerf.Dataset(_support.scene_dir())
        res = ds._res
        img = ds.image(0)
        view = img[1:3]
        values = flat(img)
        del img
        del ds
        gc.collect()
        self.assertIsNotNone(res.ptr)
        self.assertEqual(flat(view), values[48:144])
        del view
        gc.collect()
        self.assertIsNone(res.ptr)

    def test_read_png_buffer_is_freed(self):
        path = os.path.join(_support.scene_dir(), "train", "r_0.png")
        for _ in range(20):
            img = nerf.read_png(path)
            self.assertEqual(len(flat(img)), 16 * 16 * 4)
        del img
        gc.collect()


class Exit(TestCase):
    def test_interpreter_exit_with_live_handles(self):
        script = textwrap.dedent("""
            import nerf
            ds = nerf.Dataset(%r)
            model = nerf.Model(preset="tiny")
            sampler = nerf.Sampler.for_dataset(ds, n_coarse=4, n_fine=4)
            r = nerf.Renderer(model, sampler, progress=lambda p: None)
            t = nerf.Trainer(model, ds, sampler, batch_rays=16)
            t.step()
            model.cycle = (r, t)
            img = ds.image(0)
            png = nerf.read_png(%r)
            model.close()
            print("done")
        """) % (_support.scene_dir(),
                os.path.join(_support.scene_dir(), "train", "r_0.png"))
        out = subprocess.run([sys.executable, "-c", script],
                             capture_output=True, text=True, timeout=120)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertEqual(out.stdout.strip(), "done")
        self.assertEqual(out.stderr, "")


if __name__ == "__main__":
    _support.main()
