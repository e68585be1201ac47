"""Finding and loading the libnerf shared library.

Search order:

1. ``NERF_LIBRARY``: a path to the shared library.  When it is set, nothing
   else is tried, so a wrong value fails loudly instead of silently picking
   up another copy.
2. For a package installed by ``meson install``: the library installed
   with it.  ``meson install`` writes ``nerf/_config.py`` with the
   configured library directory and package directory; the library is
   looked for first where the first lies relative to this package's actual
   place (so a tree staged with ``--destdir``, or moved as a whole, still
   finds its own copy), then at the configured path itself.
3. The installed library: ``libnerf.so.0`` through the dynamic loader's
   search path, then whatever ``ctypes.util.find_library("nerf")`` finds.
4. Only for the package in the source tree (no ``_config.py``): a build
   tree next to it: ``build/release/lib``, ``build/lib``, then any other
   ``build*/lib`` or ``build*/*/lib`` directory of the repository holding
   ``bindings/python``.

The library's major version must be the one this binding was written for
(:data:`EXPECTED_MAJOR`); anything else is refused at import time, since
libnerf changes its ABI only with its major version (and, while at 0.x,
the binding is updated in the same tree as the library).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys
from pathlib import Path
from typing import Any, List, Optional, Tuple

try:
    # Written by meson install; absent in the source tree.
    from . import _config
except ImportError:
    _config = None

#: The major version of libnerf this binding speaks to.
EXPECTED_MAJOR = 0

_SONAMES = {
    "linux": ["libnerf.so.%d" % EXPECTED_MAJOR, "libnerf.so"],
    "darwin": ["libnerf.%d.dylib" % EXPECTED_MAJOR, "libnerf.dylib"],
    "win32": ["nerf-%d.dll" % EXPECTED_MAJOR, "nerf.dll", "libnerf.dll"],
}

_HINT = ("Set NERF_LIBRARY to the path of the shared library (for example "
         "NERF_LIBRARY=build/release/lib/libnerf.so.0 after `meson setup "
         "build/release && ninja -C build/release`), or install libnerf "
         "(`meson install`, then `ldconfig`).")


def _platform_names() -> List[str]:
    for prefix, names in _SONAMES.items():
        if sys.platform.startswith(prefix):
            return names
    return _SONAMES["linux"]


def _installed_candidates(config: Any = None,
                          here: Optional[Path] = None) -> List[Path]:
    """Where the library installed with this package should be.

    Args:
        config: the generated ``_config`` module (or anything with
            ``LIBDIR`` and ``PACKAGE_DIR``); ``None`` for this package's.
        here: the package's actual directory; ``None`` for this one's.
    """
    config = config if config is not None else _config
    if config is None:
        return []
    # As imported, not resolved: the layout the install made is what counts.
    if here is None:
        here = Path(os.path.abspath(__file__)).parent
    libdir = Path(config.LIBDIR)
    relative = os.path.relpath(config.LIBDIR, config.PACKAGE_DIR)
    dirs = [Path(os.path.normpath(here / relative))]
    if libdir not in dirs:
        dirs.append(libdir)
    return [d / name for d in dirs for name in _platform_names()]


def _build_tree_candidates() -> List[Path]:
    """Shared libraries in build directories of this source tree."""
    # nerf/_loader.py -> nerf -> python -> bindings -> repository root
    root = Path(__file__).resolve().parents[3]
    dirs = [root / "build" / "release" / "lib", root / "build" / "lib"]
    for pattern in ("build*/lib", "build*/*/lib"):
        for d in sorted(root.glob(pattern)):
            if d not in dirs:
                dirs.append(d)
    return [d / name for d in dirs for name in _platform_names()
            if (d / name).exists()]


def find_and_load() -> Tuple[ctypes.CDLL, str]:
    """Load libnerf; return the library and the path or name it came from.

    Raises:
        ImportError: nothing could be loaded; the message says what was
            tried and what to set.
    """
    mode = getattr(os, "RTLD_NOW", 0) | getattr(ctypes, "RTLD_LOCAL", 0)
    env = os.environ.get("NERF_LIBRARY")
    if env:
        try:
            return ctypes.CDLL(env, mode=mode), env
        except OSError as err:
            raise ImportError(
                "libnerf: NERF_LIBRARY=%s could not be loaded: %s. Point "
                "NERF_LIBRARY at a built libnerf shared library "
                "(lib/libnerf.so.0 in a meson build directory)."
                % (env, err)) from err

    tried: List[str] = []
    errors: List[str] = []
    names: List[str] = list(_platform_names())
    found = ctypes.util.find_library("nerf")
    if found and found not in names:
        names.append(found)
    installed = [str(p) for p in _installed_candidates() if p.exists()]
    build_tree = ([] if _config is not None else
                  [str(p) for p in _build_tree_candidates()])
    candidates = installed + names + build_tree
    for candidate in candidates:
        tried.append(candidate)
        try:
            return ctypes.CDLL(candidate, mode=mode), candidate
        except OSError as err:
            # "cannot open" just means "not here"; anything else is news.
            if "No such file" not in str(err) and "not found" not in str(err):
                errors.append("%s: %s" % (candidate, err))
    detail = ("; errors: " + "; ".join(errors)) if errors else ""
    raise ImportError("libnerf: shared library not found (tried %s)%s. %s"
                      % (", ".join(tried), detail, _HINT))


def check_version(number: int, where: str) -> None:
    """Refuse a library whose major version is not :data:`EXPECTED_MAJOR`.

    Args:
        number: ``nerf_version_number()``, major * 10000 + minor * 100 +
            patch.
        where: the library's path or name, for the message.

    Raises:
        ImportError: the major versions differ.
    """
    major, rest = divmod(int(number), 10000)
    minor, patch = divmod(rest, 100)
    if major != EXPECTED_MAJOR:
        raise ImportError(
            "libnerf: %s is version %d.%d.%d but this Python binding needs "
            "major version %d; use the binding shipped with that library, or "
            "set NERF_LIBRARY to a libnerf %d.x."
            % (where, major, minor, patch, EXPECTED_MAJOR, EXPECTED_MAJOR))
