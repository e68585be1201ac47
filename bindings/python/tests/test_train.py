"""nerf.Trainer: steps, runs, callbacks, cancellation and checkpoints."""

import math
import os
import signal
import threading

import _support
from _support import TestCase, nerf


class Boom(Exception):
    """Raised by test callbacks."""


def trainer(model, ds, sampler, **kw):
    kw.setdefault("batch_rays", 32)
    kw.setdefault("precrop_steps", 1)
    return nerf.Trainer(model, ds, sampler, **kw)


class Training(TestCase):
    def test_step_and_run(self):
        ds, model, sampler = _support.tiny_setup(seed=1)
        with trainer(model, ds, sampler) as t:
            stats = t.step()
            self.assertIsInstance(stats, nerf.TrainStats)
            self.assertEqual(stats.step, 1)
            self.assertEqual(model.step, 1)
            self.assertGreater(stats.loss, 0)
            self.assertTrue(math.isfinite(stats.psnr))
            self.assertTrue(math.isfinite(stats.psnr_coarse))
            self.assertAlmostEqual(stats.learning_rate, 5e-3)  # tiny preset's
            seen = []
            last = t.run(3, progress=seen.append)
            self.assertEqual(last.step, 4)
            self.assertEqual([p.done for p in seen], [1, 2, 3])
            self.assertTrue(all(p.kind == "train" and p.total == 3
                                for p in seen))
            self.assertAlmostEqual(seen[-1].loss, last.loss)
            self.assertAlmostEqual(seen[-1].psnr, last.psnr)
            t.progress = seen.append
            t.run(1)
            self.assertEqual(len(seen), 4)
            self.assertEqual(t.progress, seen.append)
        for h in (ds, model, sampler):
            h.close()

    def test_same_seed_same_run(self):
        results = []
        for _ in range(2):
            ds, model, sampler = _support.tiny_setup(seed=7)
            with trainer(model, ds, sampler) as t:
                results.append([t.step().loss for _ in range(2)])
        self.assertEqual(results[0], results[1])

    def test_bad_options(self):
        ds, model, sampler = _support.tiny_setup()
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            trainer(model, ds, sampler, batch_rays=0)
        with self.assertRaises(TypeError):
            trainer(model, ds, sampler, no_such_option=1)
        with self.assertRaises(TypeError):
            nerf.Trainer(model, sampler, ds)

    def test_random_background(self):
        # The built-in scene's images have alpha, so the option changes the
        # targets (and the loss), deterministically; 0 or 1 only.
        losses = []
        for rb in (0, 1, 1):
            ds, model, sampler = _support.tiny_setup(seed=3)
            with trainer(model, ds, sampler, random_background=rb) as t:
                losses.append(t.step().loss)
        self.assertNotEqual(losses[0], losses[1])
        self.assertEqual(losses[1], losses[2])
        self.assertEqual(nerf.TrainerOptions().random_background, 0)
        ds, model, sampler = _support.tiny_setup()
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "random_background"):
            trainer(model, ds, sampler, random_background=2)

    def test_appearance_codes(self):
        # A code per training image, kept by checkpoints, chosen by the
        # renderer's appearance option.
        path = os.path.join(_support.tmpdir(), "codes.nerf")
        ds, model, sampler = _support.tiny_setup(seed=2)
        self.assertEqual(model.appearance_count, 0)
        self.assertEqual(model.appearance_code(), (0.0, 0.0, 0.0))
        with trainer(model, ds, sampler, appearance_codes=1) as t:
            # The codes are held for a model's first 100 steps.
            t.run(105)
        self.assertEqual(model.appearance_count, len(ds))
        self.assertIn("appearance", model.contents)
        codes = [model.appearance_code(i) for i in range(len(ds))]
        self.assertEqual(len(codes[0]), nerf.APPEARANCE_CODE_FLOATS)
        self.assertNotEqual(codes[0], codes[1])
        neutral = model.appearance_code()
        for k in range(3):
            mean = sum(c[k] for c in codes) / len(codes)
            self.assertAlmostEqual(neutral[k], mean, places=5)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "appearance"):
            model.appearance_code(len(ds))
        model.save(path)
        with nerf.Model.load(path) as back:
            self.assertEqual(back.appearance_code(1), codes[1])
        cam = ds.camera(0)
        with nerf.Renderer(model, sampler) as r:
            plain = r.render_image(cam).rgb
        with nerf.Renderer(model, sampler,
                           appearance=nerf.appearance_of(1)) as r:
            own = r.render_image(cam).rgb
        self.assertNotEqual(_support.flat(plain), _support.flat(own))
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "appearance"):
            nerf.Renderer(model, sampler,
                          appearance=nerf.appearance_of(len(ds)))
        for h in (ds, model, sampler):
            h.close()

    def test_checkpoint(self):
        path = os.path.join(_support.tmpdir(), "ckpt.nerf")
        ds, model, sampler = _support.tiny_setup()
        opts = nerf.TrainerOptions(checkpoint_path=path)
        self.assertEqual(opts.to_dict()["checkpoint_path"], path)
        with trainer(model, ds, sampler, checkpoint_path=path,
                     checkpoint_every=1) as t:
            t.run(2)
        self.assertTrue(os.path.isfile(path))
        with nerf.Model.load(path) as back:
            self.assertEqual(back.step, 2)
        # A path that cannot be written is refused when the trainer is
        # made, not at its first save.
        bad = os.path.join(_support.tmpdir(), "missing-dir", "c.nerf")
        with self.assertNerfError(nerf.NerfIOError, nerf.EIO, "missing-dir"):
            trainer(model, ds, sampler, checkpoint_path=bad)

    def test_timed_checkpoints(self):
        # A save once checkpoint_seconds have passed since the last: a
        # tiny interval saves after every step, which a progress callback
        # sees on disk.
        path = os.path.join(_support.tmpdir(), "timed.nerf")
        ds, model, sampler = _support.tiny_setup()
        self.assertEqual(nerf.TrainerOptions().checkpoint_seconds, 0.0)
        seen = []

        def on_progress(p):
            with nerf.Model.load(path) as back:
                seen.append(back.step)

        with trainer(model, ds, sampler, checkpoint_path=path,
                     checkpoint_seconds=1e-9) as t:
            t.run(2, progress=on_progress)
        self.assertEqual(seen, [1, 2])
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "checkpoint_seconds"):
            trainer(model, ds, sampler, checkpoint_path=path,
                    checkpoint_seconds=-1.0)

    def test_run_for_fits_and_records_the_schedule(self):
        ds, model, sampler = _support.tiny_setup(seed=2)
        self.assertEqual(model.schedule["state"], "steps")
        self.assertEqual(nerf.PARAMS["decay_start"], nerf.PARAM_DECAY_START)
        with trainer(model, ds, sampler) as t:
            try:
                t.run_for(0.4)
            except nerf.NerfCancelled:
                # Out of time on a busy machine: the run goes on to the
                # recorded length.
                t.run_for(30.0)
            sc = model.schedule
            self.assertEqual(sc["state"], "fitted")
            self.assertEqual(sc["budget_seconds"], 0.4)
            self.assertGreater(sc["steps_per_second"], 0)
            self.assertEqual(model.step, sc["total_steps"])
            self.assertEqual(model.get_param("decay_start"), sc["fit_step"])
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "positive finite"):
                t.run_for(0.0)
        # A schedule set by hand replaces the fitted one.
        model.set_param("decay_steps", 500)
        self.assertEqual(model.schedule["state"], "steps")
        self.assertEqual(model.schedule["total_steps"], 500)


class Callbacks(TestCase):
    def setUp(self):
        self.ds, self.model, self.sampler = _support.tiny_setup()
        self.t = trainer(self.model, self.ds, self.sampler)

    def tearDown(self):
        self.t.close()

    def test_cancel_from_callback(self):
        with self.assertNerfError(nerf.NerfCancelled, nerf.ECANCELLED):
            self.t.run(5, progress=lambda p: p.done >= 2)
        self.assertEqual(self.model.step, 2)   # stopped after whole steps

    def test_raising_callback_is_reraised(self):
        def bad(p):
            raise Boom("step %d" % p.done)

        with self.assertRaises(Boom) as cm:
            self.t.run(5, progress=bad)
        self.assertEqual(str(cm.exception), "step 1")
        self.assertEqual(self.model.step, 1)
        # The trainer is usable again, with nothing left pending.
        self.assertEqual(self.t.run(1).step, 2)

    def test_ctrl_c_stops_after_the_step(self):
        def press_ctrl_c(p):
            os.kill(os.getpid(), signal.SIGINT)

        with self.assertRaises(KeyboardInterrupt):
            self.t.run(5, progress=press_ctrl_c)
        self.assertEqual(self.model.step, 2)
        self.assertIs(signal.getsignal(signal.SIGINT),
                      signal.default_int_handler)

    def test_step_inside_callback_is_refused(self):
        with self.assertRaises(RuntimeError):
            self.t.run(3, progress=lambda p: self.t.step())
        self.assertEqual(self.model.step, 1)

    def test_cancel_from_another_thread(self):
        started = threading.Event()
        release = threading.Event()

        def slow(p):
            started.set()
            release.wait(10)

        outcome = {}

        def run():
            try:
                self.t.run(50, progress=slow)
                outcome["rc"] = "done"
            except nerf.NerfCancelled:
                outcome["rc"] = "cancelled"

        th = threading.Thread(target=run)
        th.start()
        self.assertTrue(started.wait(30))
        self.t.cancel()
        release.set()
        th.join(60)
        self.assertEqual(outcome.get("rc"), "cancelled")
        self.assertLess(self.model.step, 50)
        self.t.close()
        self.t.cancel()   # closed: a no-op


if __name__ == "__main__":
    _support.main()
