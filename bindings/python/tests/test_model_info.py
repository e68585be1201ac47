"""What a model says of itself: Model.options by name, weights-only exports
(Model.export, Model.contents) and the render settings that let
nerf.Renderer(model) render a model without being told its scene."""

import os

import _support
from _support import TestCase, flat, nerf


def camera(size=8):
    return nerf.Camera.from_fov(size, size, 40.0, eye=(0.0, -4.0, 1.0))


class OptionNames(TestCase):
    def test_repr_and_attributes_show_names(self):
        m = nerf.Model(preset="fast", hash_log2_size=12, space="ndc")
        opts = m.options
        text = repr(opts)
        for part in ("encoding='hashgrid'", "matmul='fp32'", "space='ndc'",
                     "dir_encoding='spherical_harmonics'",
                     "density_activation='exp'",
                     "encoding_flags='include_input'"):
            self.assertIn(part, text)
        self.assertNotIn("encoding=2", text)
        self.assertEqual(str(opts.encoding), "hashgrid")
        self.assertEqual(opts.encoding.name, "hashgrid")
        # Still the ints the C API and the constants use.
        self.assertEqual(opts.encoding, nerf.ENCODING_HASHGRID)
        self.assertEqual(opts.encoding, "hashgrid")
        self.assertNotEqual(opts.encoding, "frequency")
        self.assertEqual(int(opts.space), nerf.SPACE_NDC)
        self.assertEqual(opts.to_dict()["matmul"], nerf.MATMUL_FP32)
        self.assertEqual(hash(opts.space), hash(nerf.SPACE_NDC))

    def test_set_by_name_or_number(self):
        opts = nerf.ModelOptions(encoding="hashgrid", space="unbounded",
                                 encoding_flags="include_input|scale_pi")
        self.assertEqual(int(opts.encoding), nerf.ENCODING_HASHGRID)
        self.assertEqual(int(opts.space), nerf.SPACE_UNBOUNDED)
        self.assertEqual(int(opts.encoding_flags), 3)
        self.assertEqual(str(opts.encoding_flags), "include_input|scale_pi")
        opts.matmul = nerf.MATMUL_FP32
        opts.density_activation = "exp"
        self.assertEqual(int(opts.density_activation), nerf.DENSITY_EXP)
        with self.assertRaises(ValueError) as cm:
            opts.space = "sphere"
        self.assertIn("box", str(cm.exception))
        # The struct still goes to the library as is.
        opts.hash_log2_size = 12
        opts.space = "box"
        m = nerf.Model(**{k: v for k, v in opts.to_dict().items()})
        self.assertEqual(m.options.encoding, "hashgrid")


def trained(steps=2):
    """A tiny model trained on the 16 x 16 Blender scene, and the sampler
    and background it was trained with."""
    ds, model, sampler = _support.tiny_setup()
    with nerf.Trainer(model, ds, sampler, batch_rays=64) as t:
        for _ in range(steps):
            t.step()
    return model, sampler


class Export(TestCase):
    def test_weights_only_export(self):
        model, _ = trained()
        self.assertEqual(model.contents,
                         {"optimizer", "render_settings", "data_record",
                          "batch_record"})
        self.assertIn("images of 16x16 (blender", model.training_data)
        self.assertEqual(model.training_batch, (64, 0))
        full = os.path.join(_support.tmpdir(), "full.nerf")
        part = os.path.join(_support.tmpdir(), "weights.nerf")
        model.save(full)
        model.export(part)
        print("checkpoint %d bytes, export %d bytes"
              % (os.path.getsize(full), os.path.getsize(part)))
        self.assertLess(2 * os.path.getsize(part), os.path.getsize(full))
        back = nerf.Model.load(part)
        self.assertEqual(back.contents, {"render_settings", "data_record",
                                         "batch_record"})
        self.assertEqual(back.training_data, model.training_data)
        self.assertEqual(back.training_batch, (64, 0))
        fresh = nerf.Model("tiny")
        self.assertIsNone(fresh.training_batch)
        self.assertNotIn("batch_record", fresh.contents)
        self.assertEqual(back.step, 2)
        pos = [[0.1, 0.2, 0.3]]
        self.assertEqual(flat(back.query(pos, [[0.0, 0.0, 1.0]])[0]),
                         flat(model.query(pos, [[0.0, 0.0, 1.0]])[0]))
        ds, _, sampler = _support.tiny_setup()
        with self.assertRaises(nerf.NerfInvalidArgument) as cm:
            nerf.Trainer(back, ds, sampler)
        self.assertIn("weights-only", str(cm.exception))


class RenderSettings(TestCase):
    def test_renderer_of_a_model_alone(self):
        model, sampler = trained()
        so, ro = model.render_settings()
        self.assertEqual((so.n_coarse, so.n_fine), (8, 8))
        self.assertEqual(ro.white_background, 1)  # a Blender scene
        with nerf.Renderer(model, sampler, white_background=1) as r:
            want = flat(r.render_image(camera()).rgb)
        with nerf.Renderer(model, sampler) as r:
            black = flat(r.render_image(camera()).rgb)
        self.assertNotEqual(want, black)
        path = os.path.join(_support.tmpdir(), "settings.nerf")
        model.export(path)
        for m in (model, nerf.Model.load(path)):
            with nerf.Renderer(m) as r:
                self.assertEqual(flat(r.render_image(camera()).rgb), want)
        # Keyword fields still win.
        with nerf.Renderer(model, white_background=0) as r:
            self.assertEqual(flat(r.render_image(camera()).rgb), black)

    def test_forward_facing_model_alone(self):
        """An LLFF model renders through its own NDC frustum on black, as
        a sampler made from its dataset does."""
        path = os.path.join(_support.tmpdir(), "ff")
        nerf.write_scene(path, width=16, height=12, n_train=4, n_test=1,
                         capture="forward", layout="llff")
        ds = nerf.Dataset(path, "train")
        self.assertTrue(ds.is_ndc)
        model = nerf.Model(preset="tiny")
        sampler = nerf.Sampler.for_dataset(ds, preset="tiny", n_coarse=8,
                                           n_fine=8)
        with nerf.Trainer(model, ds, sampler, batch_rays=64) as t:
            t.step()
        so, ro = model.render_settings()
        self.assertEqual((so.ndc, so.ndc_width, so.ndc_height), (1, 16, 12))
        self.assertEqual(ro.white_background, 0)
        cam = nerf.Dataset(path, "test").camera(0)
        with nerf.Renderer(model, sampler, white_background=0) as r:
            want = flat(r.render_image(cam).rgb)
        path = os.path.join(_support.tmpdir(), "ff.nerf")
        model.save(path)
        with nerf.Renderer(nerf.Model.load(path)) as r:
            self.assertEqual(flat(r.render_image(cam).rgb), want)

    def test_set_render_settings(self):
        m = nerf.Model(preset="tiny")
        m.set_render_settings(nerf.Sampler(n_coarse=4, n_fine=0, t_near=1,
                                           t_far=3), 0)
        self.assertIn("render_settings", m.contents)
        so, ro = m.render_settings()
        self.assertEqual((so.n_coarse, so.n_fine, so.t_near, so.t_far),
                         (4, 0, 1.0, 3.0))
        self.assertEqual(ro.white_background, 0)
        with self.assertRaises(nerf.NerfInvalidArgument):
            m.set_render_settings(nerf.SamplerOptions(n_coarse=1), 0)
        with self.assertRaises(TypeError):
            m.set_render_settings("sampler", 0)

    def test_untrained_model_gets_a_guess(self):
        m = nerf.Model(preset="tiny")
        self.assertEqual(m.contents, {"optimizer"})
        # A hash-grid model corrects its table's parameters by their own
        # update counts (since 0.10).
        with nerf.Model(preset="fast", hash_log2_size=10) as g:
            self.assertEqual(g.contents, {"optimizer", "adam_corrections"})
        so, ro = m.render_settings()
        self.assertEqual((so.n_coarse, so.n_fine), (32, 64))
        self.assertEqual((so.t_near, so.t_far, ro.white_background),
                         (2.0, 6.0, 1))
        with nerf.Renderer(m) as r:
            r.render_image(camera(4))


if __name__ == "__main__":
    _support.main()
