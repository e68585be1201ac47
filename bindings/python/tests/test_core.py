"""Process-wide functions, error mapping, logging and declaration coverage."""

import errno
import os
import pickle
import re
import subprocess
import sys
import tempfile
import threading

import _support
from _support import TestCase, nerf

from nerf import _capi, errors

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = os.path.join(HERE, "..", "nerf")
MAPFILE = os.path.join(HERE, "..", "..", "..", "lib", "libnerf.map")


class Versions(TestCase):
    def test_version(self):
        major, minor, patch = nerf.version()
        self.assertEqual(major, nerf.EXPECTED_MAJOR)
        self.assertEqual(nerf.version_number(),
                         major * 10000 + minor * 100 + patch)
        self.assertEqual(nerf.version_string(),
                         "%d.%d.%d" % (major, minor, patch))
        self.assertEqual(nerf.__version__, nerf.version_string())

    def test_build_info(self):
        info = nerf.build_info()
        self.assertIn(nerf.version_string(), info)
        self.assertTrue(nerf.library_path())


class Errors(TestCase):
    def test_status_strings(self):
        self.assertEqual(nerf.status_string(nerf.EINVAL), "invalid argument")
        self.assertEqual(nerf.status_string(-1000), "unknown status")
        for code in range(nerf.EUNRECOGNISED, nerf.OK + 1):
            self.assertTrue(nerf.status_string(code))

    def test_codes_and_classes(self):
        pairs = [(nerf.ERROR, nerf.NerfInternalError),
                 (nerf.EINVAL, nerf.NerfInvalidArgument),
                 (nerf.ENOMEM, nerf.NerfNoMemory),
                 (nerf.EIO, nerf.NerfIOError),
                 (nerf.EFORMAT, nerf.NerfFormatError),
                 (nerf.ECANCELLED, nerf.NerfCancelled),
                 (nerf.EVERSION, nerf.NerfVersionError),
                 (nerf.ENOENT, nerf.NerfNotFound),
                 (nerf.EUNRECOGNISED, nerf.NerfUnrecognised)]
        for code, cls in pairs:
            err = errors.error_for_status(code, "boom", "nerf_x")
            self.assertIs(type(err), cls)
            self.assertEqual(err.code, code)
            self.assertEqual(err.message, "boom")
            self.assertEqual(err.function, "nerf_x")
            self.assertIn("boom", str(err))
        self.assertIsInstance(errors.error_for_status(nerf.EINVAL),
                              ValueError)
        self.assertIsInstance(errors.error_for_status(nerf.ENOMEM),
                              MemoryError)
        # A code newer than the binding still gives a NerfError.
        err = errors.error_for_status(-99)
        self.assertIs(type(err), nerf.NerfError)
        self.assertEqual(err.message, "unknown status")

    def test_missing_and_unrecognised_files(self):
        # A missing file is Python's FileNotFoundError (and still the
        # NerfIOError it was before 0.4); a file or folder of the wrong
        # kind is a NerfFormatError; neither reads as an I/O failure.
        self.assertEqual(nerf.status_string(nerf.ENOENT),
                         "no such file or folder")
        with tempfile.TemporaryDirectory() as tmp:
            missing = os.path.join(tmp, "nope.nerf")
            with self.assertRaises(FileNotFoundError) as ctx:
                nerf.Model.load(missing)
            err = ctx.exception
            self.assertIsInstance(err, nerf.NerfNotFound)
            self.assertIsInstance(err, nerf.NerfIOError)
            self.assertEqual(err.code, nerf.ENOENT)
            self.assertEqual(err.errno, errno.ENOENT)
            self.assertIn("nope.nerf", str(err))
            with self.assertRaises(FileNotFoundError):
                nerf.Dataset(os.path.join(tmp, "no-scene"))
            with self.assertRaises(nerf.NerfUnrecognised) as ctx:
                nerf.Dataset(tmp)
            self.assertIsInstance(ctx.exception, nerf.NerfFormatError)
            self.assertIn("not a known dataset layout", str(ctx.exception))
            other = os.path.join(tmp, "photo.nerf")
            with open(other, "wb") as f:
                f.write(b"\x89PNG\r\n\x1a\n not a model")
            with self.assertRaises(nerf.NerfUnrecognised) as ctx:
                nerf.Model.load(other)
            self.assertIn("not a libnerf checkpoint", str(ctx.exception))

    def test_pickle(self):
        err = errors.error_for_status(nerf.EIO, "x.png: cannot open")
        back = pickle.loads(pickle.dumps(err))
        self.assertIs(type(back), nerf.NerfIOError)
        self.assertEqual((back.code, back.message), (err.code, err.message))

    def test_status_becomes_exception_with_library_message(self):
        nerf.clear_error()
        self.assertEqual(nerf.last_error(), "")
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "nerf_hooks"):
            _capi.lib.nerf_hooks_init(None, 0)
        # The binding read the same message the library still holds.
        self.assertIn("nerf_hooks", nerf.last_error())
        nerf.clear_error()
        self.assertEqual(nerf.last_error(), "")

    def test_messages_are_per_thread(self):
        seen = {}

        def worker():
            try:
                nerf.param_bounds(12345)
            except nerf.NerfInvalidArgument as err:
                seen["worker"] = err.message

        with self.assertRaises(nerf.NerfIOError) as cm:
            nerf.Model.load(os.path.join(_support.tmpdir(), "absent.nerf"))
        t = threading.Thread(target=worker)
        t.start()
        t.join()
        self.assertIn("absent.nerf", cm.exception.message)
        self.assertIn("absent.nerf", nerf.last_error())
        self.assertIn("12345", seen["worker"])

    def test_param_bounds(self):
        lo, hi = nerf.param_bounds("learning_rate")
        self.assertLess(lo, 5e-4)
        self.assertGreater(hi, 5e-4)
        self.assertEqual(nerf.param_bounds(nerf.PARAM_ADAM_EPS),
                         nerf.param_bounds("adam_eps"))
        with self.assertRaises(ValueError):
            nerf.param_bounds("no_such_param")
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.param_bounds(99)


class Logging(TestCase):
    def tearDown(self):
        nerf.set_log_handler(None)

    def test_default_handler(self):
        lines = []
        nerf.set_log_handler(lambda level, msg: lines.append((level, msg)),
                             nerf.LOG_DEBUG)
        nerf.Dataset(_support.scene_dir(), "train").close()
        self.assertTrue(lines)
        self.assertTrue(all(isinstance(m, str) for _, m in lines))
        self.assertTrue(any(level == nerf.LOG_INFO for level, _ in lines))
        count = len(lines)
        nerf.set_log_handler(None)
        nerf.Dataset(_support.scene_dir(), "train").close()
        self.assertEqual(len(lines), count)

    def test_per_handle_log_wins(self):
        default, own = [], []
        nerf.set_log_handler(lambda level, msg: default.append(msg))
        nerf.Dataset(_support.scene_dir(), "train",
                     log=lambda level, msg: own.append(msg)).close()
        self.assertTrue(own)
        self.assertEqual(default, [])
        # Filtered out below the handle's threshold.
        quiet = []
        nerf.Dataset(_support.scene_dir(), "train",
                     log=lambda level, msg: quiet.append(msg),
                     log_level=nerf.LOG_ERROR).close()
        self.assertEqual(quiet, [])
        with self.assertRaises(ValueError):
            nerf.Dataset(_support.scene_dir(), log_level=nerf.LOG_INFO)

    def test_stderr_logger(self):
        code = ("import nerf; nerf.log_stderr(nerf.LOG_WARN, 'hello'); "
                "nerf.log_to_stderr(nerf.LOG_INFO); "
                "nerf.Dataset(%r, 'train').close()" % _support.scene_dir())
        out = subprocess.run([sys.executable, "-c", code],
                             capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("libnerf: ", out.stderr)
        self.assertIn("hello", out.stderr)
        self.assertGreater(out.stderr.count("libnerf: "), 1)


class Declarations(TestCase):
    def exported(self):
        with open(MAPFILE, encoding="utf-8") as f:
            text = f.read()
        return set(re.findall(r"^\s*(nerf_\w+);", text, re.M))

    def test_every_exported_function_is_declared(self):
        exported = self.exported()
        self.assertTrue(exported)
        declared = set(_capi.FUNCTION_NAMES)
        self.assertEqual(exported - declared, set(),
                         "functions the binding does not declare")
        self.assertEqual(declared - exported, set(),
                         "declared functions the library does not export")
        for name in declared:
            fn = getattr(_capi.lib, name)
            self.assertIsNotNone(fn.argtypes, name)
            self.assertTrue(hasattr(fn, "restype"), name)

    def test_every_function_is_wrapped(self):
        """Each C function is called somewhere in the package."""
        source = ""
        for name in sorted(os.listdir(PACKAGE)):
            if name.endswith(".py") and name != "_capi.py":
                with open(os.path.join(PACKAGE, name), encoding="utf-8") as f:
                    source += f.read()
        used = set(re.findall(r"\b(nerf_\w+)\b", source))
        # _capi itself calls nerf_version_number (the import-time check) and
        # hands nerf_status_string and nerf_last_error to the error module.
        # The *_init functions are named by the struct mirrors' _c_init_.
        missing = set(_capi.FUNCTION_NAMES) - used - {
            "nerf_version_number", "nerf_status_string", "nerf_last_error"}
        self.assertEqual(missing, set())


if __name__ == "__main__":
    _support.main()
