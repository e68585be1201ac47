"""nerf.Model: creation, options, parameters, queries, save/load, npz."""

import array
import math
import os

import _support
from _support import TestCase, flat, nerf, shape


def points(n):
    """n positions inside the scene and unit directions, as lists."""
    pos = [[0.1 * i - 0.5, 0.05 * i, -0.02 * i] for i in range(n)]
    dirs = [[0.0, 0.6, 0.8] for _ in range(n)]
    return pos, dirs


class Create(TestCase):
    def test_presets_and_options(self):
        ref = nerf.ModelOptions()
        self.assertEqual((ref.depth, ref.width), (8, 256))
        with nerf.Model(preset="tiny", seed=3) as tiny:
            opts = tiny.options
            self.assertLess(opts.width, ref.width)
            self.assertEqual(opts.seed, 3)
            self.assertFalse(opts.hooks)
            self.assertGreater(tiny.param_count, 0)
            self.assertEqual(tiny.step, 0)
            tiny_count = tiny.param_count
        with nerf.Model.create(preset=nerf.PRESET_TINY, width=32,
                               use_fine=0) as m:
            self.assertEqual(m.options.width, 32)
            self.assertEqual(m.options.use_fine, 0)
            self.assertLess(m.param_count, tiny_count)

    def test_bad_options(self):
        with self.assertRaises(TypeError):
            nerf.Model(preset="tiny", no_such_field=1)
        with self.assertRaises(ValueError):
            nerf.Model(preset="huge")
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "width"):
            nerf.Model(preset="tiny", width=0)

    def test_fast_preset(self):
        with nerf.Model(preset="fast", seed=1, hash_log2_size=12,
                        hash_levels=4) as model:
            opts = model.options
            self.assertEqual(opts.encoding, nerf.ENCODING_HASHGRID)
            self.assertEqual(opts.dir_encoding,
                             nerf.ENCODING_SPHERICAL_HARMONICS)
            self.assertEqual(opts.density_activation, nerf.DENSITY_EXP)
            self.assertEqual((opts.use_fine, opts.hash_levels), (0, 4))
            pos, dirs = points(5)
            _, sigma = model.query(pos, dirs)
            # exp activation: every density is positive.
            self.assertTrue(all(v > 0.0 for v in flat(sigma)))

    def test_options_struct(self):
        opts = nerf.ModelOptions(depth=3, seed=9)
        self.assertEqual(opts.struct_size, 128)
        d = opts.to_dict()
        self.assertEqual((d["depth"], d["seed"]), (3, 9))
        self.assertNotIn("struct_size", d)
        self.assertNotIn("reserved0", d)
        copy = opts.copy()
        copy.depth = 5
        self.assertEqual(opts.depth, 3)
        self.assertIn("depth=3", repr(opts))


class Params(TestCase):
    def test_set_get(self):
        with nerf.Model(preset="tiny") as m:
            # The tiny preset's rate (nerf_model_options_preset).
            self.assertAlmostEqual(m.get_param("learning_rate"), 5e-3)
            self.assertAlmostEqual(m.learning_rate, 5e-3)
            m.set_param("learning_rate", 1e-3)
            m.set_param(nerf.PARAM_LEARNING_RATE_FINAL, 1e-4)
            m.set_param("decay_steps", 100)
            self.assertAlmostEqual(m.get_param(nerf.PARAM_LEARNING_RATE),
                                   1e-3)
            self.assertAlmostEqual(m.get_param("learning_rate_final"), 1e-4)
            self.assertEqual(m.get_param("decay_steps"), 100)
            for name in ("adam_beta1", "adam_beta2", "adam_eps"):
                self.assertGreater(m.get_param(name), 0)
            lo, hi = nerf.param_bounds("adam_beta1")
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
                m.set_param("adam_beta1", hi + 1)
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
                m.get_param(7)
            # Weight decay: none for the paper's network, Mueller et al.'s
            # 1e-6 for a hash-grid model; 0..1.
            self.assertEqual(m.get_param("weight_decay"), 0.0)
            m.set_param(nerf.PARAM_WEIGHT_DECAY, 1e-5)
            self.assertAlmostEqual(m.get_param("weight_decay"), 1e-5)
            self.assertEqual(nerf.param_bounds("weight_decay"), (0.0, 1.0))
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
                m.set_param("weight_decay", -1e-6)
            # The weights' average over the schedule's last steps: off for
            # the paper's network, 100 steps for a hash-grid model.
            self.assertEqual(m.get_param("average_steps"), 0.0)
            self.assertEqual(nerf.PARAMS["average_steps"],
                             nerf.PARAM_AVERAGE_STEPS)
            self.assertEqual(nerf.param_bounds("average_steps"), (0.0, 1e15))
        with nerf.Model(preset="fast", hash_log2_size=10) as m:
            self.assertAlmostEqual(m.get_param("weight_decay"), 1e-6)
            self.assertEqual(m.get_param("average_steps"), 100.0)
            m.set_param("average_steps", 0)
            self.assertEqual(m.get_param("average_steps"), 0.0)


class Query(TestCase):
    def test_query(self):
        pos, dirs = points(5)
        with nerf.Model(preset="tiny", seed=1) as m:
            rgb, sigma = m.query(pos, dirs)
            self.assertEqual(shape(rgb), (5, 3))
            self.assertEqual(shape(sigma), (5,))
            self.assertTrue(all(0.0 <= v <= 1.0 for v in flat(rgb)))
            self.assertTrue(_support.all_finite(sigma))
            rgb_c, sigma_c = m.query(pos, dirs, network="coarse")
            self.assertNotEqual(flat(sigma_c), flat(sigma))
            again, _ = m.query(pos, dirs, network=nerf.NETWORK_FINE)
            self.assertEqual(flat(again), flat(rgb))
            # Flat inputs of another type give the same numbers.
            flat_pos = array.array("f", flat(pos))
            flat_dirs = array.array("f", flat(dirs))
            rgb2, _ = m.query(flat_pos, flat_dirs)
            self.assertEqual(flat(rgb2), flat(rgb))

    def test_query_errors(self):
        pos, dirs = points(4)
        with nerf.Model(preset="tiny") as m:
            with self.assertRaises(ValueError):
                m.query([1.0, 2.0], None)
            with self.assertRaises(ValueError):
                m.query(pos, dirs[:2])
            with self.assertRaises(ValueError):
                m.query(pos, dirs, network="medium")
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
                m.query(pos, None)   # this model uses view directions
        with nerf.Model(preset="tiny", use_fine=0, use_viewdirs=0) as m:
            rgb, sigma = m.query(pos)
            self.assertEqual(shape(rgb), (4, 3))
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                      "network"):
                m.query(pos, network="fine")


class Matmul(TestCase):
    """oneDNN's products (``matmul``), where this build and CPU have
    them."""

    def test_query_and_options(self):
        self.assertTrue(nerf.matmul_supported("fp32"))
        self.assertTrue(nerf.matmul_supported(nerf.MATMUL_FP32))
        self.assertFalse(nerf.matmul_supported(7))
        with self.assertRaises(ValueError):
            nerf.matmul_supported("fp16")
        self.assertEqual(nerf.ModelOptions().matmul, nerf.MATMUL_FP32)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "matmul"):
            nerf.Model(preset="tiny", matmul=5)

    def skip_unless_supported(self, kind, enum_name):
        """Where `kind` is not available, its refusal is what there is to
        test: check it, then skip."""
        if nerf.matmul_supported(kind):
            return
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  enum_name):
            nerf.Model(preset="tiny", matmul=kind)
        self.skipTest("%s products are not available here: %s"
                      % (kind, nerf.last_error()))

    def test_bf16_model(self):
        self.skip_unless_supported("bf16", "NERF_MATMUL_BF16")
        pos, dirs = points(50)
        path = os.path.join(_support.tmpdir(), "bf16.nerf")
        with nerf.Model(preset="tiny", seed=2) as f, \
                nerf.Model(preset="tiny", seed=2, matmul="bf16") as b:
            self.assertEqual(b.options.matmul, nerf.MATMUL_BF16)
            rgb_f, sigma_f = f.query(pos, dirs)
            rgb_b, sigma_b = b.query(pos, dirs)
            # Close (bf16 keeps 8 significant bits), but not the same.
            # What sets the gap is the rounding of the operands to bf16,
            # the same on every processor; the products of bf16 pairs are
            # exact in fp32, so processors differ only in the order of
            # fp32 sums, a few parts in a million of the gap.  So the gap
            # measured here (1.3e-4 on rgb, 5.9e-4 on sigma against a
            # largest sigma of 0.17) is the gap everywhere, with margins
            # of 70 and 14.  The bounds derived layer by layer are
            # test_onednn's (tests/model).
            diff = [abs(x - y) for x, y in zip(flat(rgb_b), flat(rgb_f))]
            scale = max(abs(v) for v in flat(sigma_f))
            diff_s = [abs(x - y) for x, y in zip(flat(sigma_b),
                                                 flat(sigma_f))]
            print("bf16 against fp32: rgb %.3g, sigma %.3g (largest sigma "
                  "%.3g)" % (max(diff), max(diff_s), scale))
            self.assertLess(max(diff), 0.01)
            self.assertLess(max(diff_s), 0.05 * scale)
            self.assertGreater(max(diff + diff_s), 0.0)
            b.save(path)
        with nerf.Model.load(path) as back:
            self.assertEqual(back.options.matmul, nerf.MATMUL_BF16)
            again, _ = back.query(pos, dirs)
            self.assertEqual(flat(again), flat(rgb_b))

    def test_fp32_onednn_model(self):
        self.skip_unless_supported("fp32-onednn", "NERF_MATMUL_FP32_ONEDNN")
        pos, dirs = points(50)
        path = os.path.join(_support.tmpdir(), "onednn.nerf")
        with nerf.Model(preset="tiny", seed=2) as f, \
                nerf.Model(preset="tiny", seed=2, matmul="fp32-onednn") as o:
            self.assertEqual(o.options.matmul, nerf.MATMUL_FP32_ONEDNN)
            self.assertEqual(str(o.options.matmul), "fp32-onednn")
            rgb_f, sigma_f = f.query(pos, dirs)
            rgb_o, sigma_o = o.query(pos, dirs)
            # fp32 either way: the sums' order is all that differs, and how
            # much depends on both libraries' kernels.  Each of the tiny
            # network's five products (at most 91 terms) is within
            # gamma(93) = 5.5e-6 of exact relative to its terms' sum of
            # magnitudes, and ReLU and the sigmoid only shrink differences:
            # far below half an 8-bit level of colour (what a user sees)
            # and a thousandth of the largest density.  test_onednn derives
            # the tight bound layer by layer.
            scale = max(abs(v) for v in flat(sigma_f))
            self.assertLess(max(abs(x - y) for x, y in
                                zip(flat(rgb_o), flat(rgb_f))), 0.5 / 255)
            self.assertLess(max(abs(x - y) for x, y in
                                zip(flat(sigma_o), flat(sigma_f))),
                            1e-3 * scale)
            o.save(path)
        with nerf.Model.load(path) as back:
            self.assertEqual(back.options.matmul, nerf.MATMUL_FP32_ONEDNN)
            again, _ = back.query(pos, dirs)
            self.assertEqual(flat(again), flat(rgb_o))


class SaveLoad(TestCase):
    def test_round_trip(self):
        path = os.path.join(_support.tmpdir(), "model.nerf")
        pos, dirs = points(3)
        with nerf.Model(preset="tiny", seed=4) as m:
            m.set_param("learning_rate", 2e-3)
            m.save(path)
            want = m.query(pos, dirs)
        with nerf.Model.load(path) as back:
            self.assertEqual(back.step, 0)
            self.assertAlmostEqual(back.get_param("learning_rate"), 2e-3)
            self.assertEqual(back.options.seed, 4)
            got = back.query(pos, dirs)
            self.assertEqual(flat(got[0]), flat(want[0]))
            self.assertEqual(flat(got[1]), flat(want[1]))
        lines = []
        nerf.Model.load(path, log=lambda lvl, msg: lines.append(msg)).close()

    def test_load_errors(self):
        missing = os.path.join(_support.tmpdir(), "missing.nerf")
        with self.assertNerfError(nerf.NerfNotFound, nerf.ENOENT, missing):
            nerf.Model.load(missing)
        junk = os.path.join(_support.tmpdir(), "junk.nerf")
        with open(junk, "wb") as f:
            f.write(b"this is not a checkpoint at all, just text" * 4)
        with self.assertNerfError(nerf.NerfUnrecognised, nerf.EUNRECOGNISED, junk):
            nerf.Model.load(junk)
        with nerf.Model(preset="tiny") as m:
            bad = os.path.join(_support.tmpdir(), "no-dir", "m.nerf")
            with self.assertNerfError(nerf.NerfIOError, nerf.EIO, "no-dir"):
                m.save(bad)


class ImportNpz(TestCase):
    def test_errors(self):
        missing = os.path.join(_support.tmpdir(), "missing.npz")
        with self.assertNerfError(nerf.NerfNotFound, nerf.ENOENT, missing):
            nerf.Model.import_npz(missing, preset="tiny")
        junk = os.path.join(_support.tmpdir(), "junk.npz")
        with open(junk, "wb") as f:
            f.write(b"PK not really a zip")
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT, junk):
            nerf.Model.import_npz(junk, preset="tiny")

    def test_import(self):
        if not nerf.HAVE_NUMPY:
            self.skipTest("writing an .npz needs NumPy")
        import numpy as np
        o = nerf.ModelOptions()
        lib_preset = nerf.Model(preset="tiny")
        o = lib_preset.options
        lib_preset.close()
        W, V = o.width, o.view_width
        ep = 3 * (1 + 2 * o.pos_frequencies)
        ed = 3 * (1 + 2 * o.dir_frequencies)
        arrays = {}

        def layer(name, out, inp, bias=0.0):
            arrays[name + ".weight"] = np.zeros((out, inp), np.float32)
            arrays[name + ".bias"] = np.full((out,), bias, np.float32)

        for net in ("coarse", "fine"):
            for i in range(o.depth):
                inp = ep if i == 0 else W
                if o.skip_layer and i == o.skip_layer:
                    inp = ep + W
                layer("%s.pts_linears.%d" % (net, i), W, inp)
            layer(net + ".feature_linear", W, W)
            layer(net + ".alpha_linear", 1, W, bias=1.5)
            layer(net + ".views_linears.0", V, W + ed)
            layer(net + ".rgb_linear", 3, V)
        path = os.path.join(_support.tmpdir(), "zeros.npz")
        np.savez(path, **arrays)
        with nerf.Model.import_npz(path, preset="tiny") as m:
            pos, dirs = points(2)
            rgb, sigma = m.query(pos, dirs)
            self.assertAllClose(sigma, [1.5, 1.5])
            self.assertAllClose(rgb, [0.5] * 6)   # sigmoid(0)
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT, path):
            nerf.Model.import_npz(path, preset="tiny", width=48)
        self.assertTrue(math.isfinite(float(sigma[0])))


if __name__ == "__main__":
    _support.main()
