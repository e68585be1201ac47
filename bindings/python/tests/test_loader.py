"""Finding the library, and refusing the wrong one.

Usage: test_loader.py [FAKE_LIBRARY], where FAKE_LIBRARY is a shared
library built by meson whose nerf_version_number() reports 1.2.3.
"""

import ctypes.util
import os
import subprocess
import sys
from pathlib import Path

import _support
from _support import TestCase, nerf

from nerf import _loader

FAKE = None


def import_with(library):
    """Import nerf in a fresh interpreter with NERF_LIBRARY=library."""
    env = dict(os.environ, NERF_LIBRARY=library)
    return subprocess.run([sys.executable, "-c", "import nerf"], env=env,
                          capture_output=True, text=True, timeout=60)


class Versions(TestCase):
    def test_same_major_is_accepted(self):
        _loader.check_version(nerf.version_number(), "here")
        _loader.check_version(9999, "here")

    def test_other_major_is_refused(self):
        with self.assertRaises(ImportError) as cm:
            _loader.check_version(10203, "/x/libnerf.so.1")
        text = str(cm.exception)
        for fragment in ("/x/libnerf.so.1", "1.2.3", "major version 0",
                         "NERF_LIBRARY"):
            self.assertIn(fragment, text)

    def test_fake_library_is_refused_at_import(self):
        if not FAKE:
            self.skipTest("no fake library given")
        out = import_with(FAKE)
        self.assertNotEqual(out.returncode, 0)
        self.assertIn("ImportError", out.stderr)
        self.assertIn("1.2.3", out.stderr)
        self.assertIn("major version 0", out.stderr)


class Search(TestCase):
    def test_bad_nerf_library(self):
        out = import_with("/nonexistent/libnerf.so.0")
        self.assertNotEqual(out.returncode, 0)
        self.assertIn("ImportError", out.stderr)
        self.assertIn("NERF_LIBRARY=/nonexistent/libnerf.so.0", out.stderr)

    def test_not_a_libnerf(self):
        libm = ctypes.util.find_library("m")
        if not libm:
            self.skipTest("no libm to load")
        out = import_with(libm)
        self.assertNotEqual(out.returncode, 0)
        self.assertIn("nerf_version_number", out.stderr)

    def test_nothing_found_says_what_to_set(self):
        saved = (os.environ.pop("NERF_LIBRARY", None), _loader._SONAMES,
                 _loader._build_tree_candidates, ctypes.util.find_library)
        try:
            _loader._SONAMES = {sys.platform: ["libnerf-absent.so.0"]}
            _loader._build_tree_candidates = lambda: []
            ctypes.util.find_library = lambda name: None
            with self.assertRaises(ImportError) as cm:
                _loader.find_and_load()
        finally:
            if saved[0] is not None:
                os.environ["NERF_LIBRARY"] = saved[0]
            (_, _loader._SONAMES, _loader._build_tree_candidates,
             ctypes.util.find_library) = saved
        text = str(cm.exception)
        self.assertIn("libnerf-absent.so.0", text)
        self.assertIn("Set NERF_LIBRARY", text)

    def test_build_tree_candidates(self):
        root = Path(_loader.__file__).resolve().parents[3]
        self.assertTrue((root / "include" / "nerf.h").exists())
        for path in _loader._build_tree_candidates():
            self.assertTrue(path.exists())
            self.assertEqual(path.parent.name, "lib")
            self.assertIn(path.name, _loader._platform_names())
            self.assertTrue(path.parent.parent.name.startswith("build") or
                            path.parent.parent.parent.name.startswith("build"))
            self.assertTrue(str(path).startswith(str(root)))

    def test_installed_candidates(self):
        class Config:
            LIBDIR = "/opt/p/lib/x86_64-linux-gnu"
            PACKAGE_DIR = "/opt/p/lib/python3.11/dist-packages/nerf"
        first = _loader._platform_names()[0]
        # Installed where configured: one place, the configured one.
        got = _loader._installed_candidates(Config, Path(Config.PACKAGE_DIR))
        self.assertEqual(got[0], Path(Config.LIBDIR) / first)
        self.assertEqual({p.parent for p in got}, {Path(Config.LIBDIR)})
        # Staged (--destdir) or moved with its prefix: the library at the
        # same relative place first, then the configured one.
        here = Path("/stage" + Config.PACKAGE_DIR)
        got = _loader._installed_candidates(Config, here)
        self.assertEqual(got[0], Path("/stage" + Config.LIBDIR) / first)
        self.assertEqual(got[-1].parent, Path(Config.LIBDIR))
        # The source tree's package has no _config.py: nothing installed.
        self.assertIsNone(_loader._config)
        self.assertEqual(_loader._installed_candidates(), [])

    def test_loaded_library(self):
        self.assertEqual(nerf.library_path(), os.environ["NERF_LIBRARY"])


if __name__ == "__main__":
    if len(sys.argv) > 1 and not sys.argv[1].startswith("-"):
        FAKE = sys.argv.pop(1)
    _support.main()
