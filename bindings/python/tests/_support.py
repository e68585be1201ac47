"""Shared set-up of the Python binding's tests.

Every test script imports this module first.  It

* exits with status 77 (meson's "skipped") when the build asked for it
  through ``NERF_PY_SKIP`` (a sanitizer build whose runtime cannot be
  preloaded into Python);
* imports ``nerf`` (``NERF_LIBRARY`` and ``PYTHONPATH`` come from meson);
* provides a tiny built-in scene, written once per script, and helpers that
  work the same with and without NumPy.
"""

from __future__ import annotations

import atexit
import math
import os
import shutil
import sys
import tempfile
import unittest

_skip = os.environ.get("NERF_PY_SKIP")
if _skip:
    print("SKIP: %s" % _skip)
    sys.exit(77)

import nerf  # noqa: E402  (after the skip check on purpose)

#: Size and views of the test scene: small enough for a fast suite.
SCENE = dict(width=16, height=16, n_train=3, n_val=1, n_test=2, seed=0)

_scene_dir = None
_tmp_root = None


def tmpdir() -> str:
    """A temporary folder for this script, removed at exit."""
    global _tmp_root
    if _tmp_root is None:
        _tmp_root = tempfile.mkdtemp(prefix="nerf-py-")
        atexit.register(shutil.rmtree, _tmp_root, True)
    return _tmp_root


def scene_dir() -> str:
    """The built-in scene at 16 x 16 pixels, written on first use."""
    global _scene_dir
    if _scene_dir is None:
        path = os.path.join(tmpdir(), "scene")
        nerf.write_scene(path, **SCENE)
        _scene_dir = path
    return _scene_dir


def tiny_setup(seed: int = 0):
    """(train dataset, tiny model, sampler with few samples)."""
    ds = nerf.Dataset(scene_dir(), "train")
    model = nerf.Model(preset="tiny", seed=seed)
    sampler = nerf.Sampler.for_dataset(ds, preset="tiny", seed=seed,
                                       n_coarse=8, n_fine=8)
    return ds, model, sampler


def flat(values) -> list:
    """A flat list of floats from an array, memoryview or nested list."""
    if hasattr(values, "tolist"):
        values = values.tolist()
    out = []

    def walk(v):
        if isinstance(v, (list, tuple)):
            for x in v:
                walk(x)
        else:
            out.append(float(v))

    walk(values)
    return out


def shape(value) -> tuple:
    """The shape of a NumPy array or memoryview."""
    return tuple(value.shape)


def all_finite(values) -> bool:
    return all(math.isfinite(v) for v in flat(values))


def expect_numpy_mode() -> bool:
    """Whether this run should use NumPy (NERF_PY_NO_NUMPY unset)."""
    return os.environ.get("NERF_PY_NO_NUMPY", "") in ("", "0")


class TestCase(unittest.TestCase):
    """unittest.TestCase with a few assertions for the binding."""

    def assertNerfError(self, cls, code, *fragments):
        """Context manager: expect ``cls`` with ``code`` whose message holds
        every fragment (such as the path of the file at fault)."""
        test = self

        class _Ctx:
            def __enter__(self):
                self.cm = test.assertRaises(cls)
                self.cm.__enter__()
                return self.cm

            def __exit__(self, *exc):
                handled = self.cm.__exit__(*exc)
                if not handled:   # another exception: let it propagate
                    return False
                err = self.cm.exception
                test.assertIsInstance(err, nerf.NerfError)
                test.assertEqual(err.code, code)
                for fragment in fragments:
                    test.assertIn(fragment, err.message)
                test.assertIn(err.message, str(err))
                return handled

        return _Ctx()

    def assertAllClose(self, a, b, tol=1e-5):
        fa, fb = flat(a), flat(b)
        self.assertEqual(len(fa), len(fb))
        for i, (x, y) in enumerate(zip(fa, fb)):
            if not abs(x - y) <= tol * max(1.0, abs(x), abs(y)):
                self.fail("element %d: %r != %r" % (i, x, y))


def main() -> None:
    """Run the script's tests; exit 0 on success, 1 on failure."""
    mode = "numpy" if nerf.HAVE_NUMPY else "no numpy"
    print("libnerf %s from %s (%s)" % (nerf.version_string(),
                                       nerf.library_path(), mode))
    unittest.main(verbosity=2)
