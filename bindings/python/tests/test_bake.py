"""nerf.Bake (libnerf 0.14): its options' defaults, and the models and
sizes it refuses, each with the library's reason.  The bake's renders are
tested in C (tests/train/test_bake.c), on models it trains."""

import _support
from _support import TestCase, nerf


class Bake(TestCase):
    def test_defaults(self):
        o = nerf.BakeOptions()
        self.assertEqual((o.subdivisions, o.sh_degree, o.directions,
                          o.march_steps), (6, 1, 8, 512))
        self.assertEqual(o.max_bytes, 2 << 30)

    def test_refuses_a_model_without_a_grid(self):
        with nerf.Model(preset="tiny", seed=1) as model:
            with self.assertRaises(nerf.NerfInvalidArgument) as cm:
                nerf.Bake(model)
            self.assertIn("occupancy grid", str(cm.exception))

    def test_refuses_a_bake_above_max_bytes(self):
        # A fresh grid marks every cell occupied: far above 1 MB.
        with nerf.Model(preset="fast", seed=1) as model:
            with self.assertRaises(nerf.NerfNoMemory) as cm:
                nerf.Bake(model, max_bytes=1 << 20)
            self.assertIn("max_bytes", str(cm.exception))

    def test_refuses_bad_options(self):
        with nerf.Model(preset="fast", seed=1) as model:
            with self.assertRaises(nerf.NerfInvalidArgument):
                nerf.Bake(model, subdivisions=0)
            with self.assertRaises(TypeError):
                nerf.Bake(model, hooks=None)


if __name__ == "__main__":
    _support.main()
