"""Status codes and the exceptions they become.

Every libnerf call that can fail returns an ``int`` status: 0 on success or
a negative code.  The binding turns each negative status into a
:class:`NerfError` whose ``code`` is that status and whose ``message`` is
the library's own explanation (``nerf_last_error()``, read on the calling
thread right after the failing call).  Each code has its own subclass, so
callers can catch exactly what they expect::

    try:
        model = nerf.Model.load("missing.nerf")
    except FileNotFoundError as err:     # nerf.NerfNotFound
        print(err.code == nerf.ENOENT, err.message)

A missing file raises :class:`NerfNotFound`, which is both a
:class:`NerfIOError` (what it was before libnerf 0.4) and Python's
``FileNotFoundError``; a file or folder of the wrong kind (not a
checkpoint, no known dataset layout) raises :class:`NerfUnrecognised`, a
:class:`NerfFormatError`.
"""

from __future__ import annotations

import errno as _errno
from typing import Dict, Optional, Type

# The values of enum nerf_status; fixed forever by the C API.
OK = 0
ERROR = -1
EINVAL = -2
ENOMEM = -3
EIO = -4
EFORMAT = -5
ECANCELLED = -6
EVERSION = -7
ENOENT = -8
EUNRECOGNISED = -9


class NerfError(Exception):
    """A libnerf call failed.

    Attributes:
        code: the negative ``nerf_status`` the call returned (compare it
            with ``nerf.EINVAL`` and friends).
        message: the library's message for the failure, naming the file,
            field or argument at fault; falls back to the status string
            when the library left none.
        function: the C function that failed, when known.
    """

    #: The status this class stands for; ``None`` for the base class.
    status: Optional[int] = None

    def __init__(self, code: int, message: str = "",
                 function: Optional[str] = None) -> None:
        self.code = int(code)
        self.message = message or status_string(self.code)
        self.function = function
        super().__init__(self.code, self.message)

    def __str__(self) -> str:
        return "%s (%s)" % (self.message, status_string(self.code))

    def __reduce__(self):  # keep pickling (multiprocessing) working
        return (type(self), (self.code, self.message, self.function))


class NerfInternalError(NerfError):
    """NERF_ERROR: an unexpected internal failure (or a non-finite loss)."""
    status = ERROR


class NerfInvalidArgument(NerfError, ValueError):
    """NERF_EINVAL: an argument or option is out of range."""
    status = EINVAL


class NerfNoMemory(NerfError, MemoryError):
    """NERF_ENOMEM: an allocation failed."""
    status = ENOMEM


class NerfIOError(NerfError):
    """NERF_EIO: a file could not be opened, read or written."""
    status = EIO


class NerfFormatError(NerfError):
    """NERF_EFORMAT: a file or buffer is malformed or corrupted."""
    status = EFORMAT


class NerfNotFound(NerfIOError, FileNotFoundError):
    """NERF_ENOENT: no such file or folder.

    Also a ``FileNotFoundError`` (``errno`` is ``errno.ENOENT``), so code
    that handles missing files the Python way handles it; ``code`` stays
    the libnerf status.
    """
    status = ENOENT

    def __init__(self, code: int, message: str = "",
                 function: Optional[str] = None) -> None:
        super().__init__(code, message, function)
        self.errno = _errno.ENOENT
        self.strerror = self.message


class NerfUnrecognised(NerfFormatError):
    """NERF_EUNRECOGNISED: the file or folder is not the kind asked for
    (no known dataset layout, not a libnerf checkpoint, a folder, FIFO,
    device or socket where a file belongs)."""
    status = EUNRECOGNISED


class NerfCancelled(NerfError):
    """NERF_ECANCELLED: a progress callback or ``cancel()`` stopped a call."""
    status = ECANCELLED


class NerfVersionError(NerfError):
    """NERF_EVERSION: a struct or file from a newer libnerf."""
    status = EVERSION


_BY_STATUS: Dict[int, Type[NerfError]] = {
    cls.status: cls
    for cls in (NerfInternalError, NerfInvalidArgument, NerfNoMemory,
                NerfIOError, NerfFormatError, NerfCancelled,
                NerfVersionError, NerfNotFound, NerfUnrecognised)
}

# Filled in by _capi once the library is loaded; until then the binding's
# own fallback text is used (only possible while importing).
_status_string_fn = None
_last_error_fn = None

_FALLBACK_TEXT = {
    OK: "success", ERROR: "internal error", EINVAL: "invalid argument",
    ENOMEM: "out of memory", EIO: "I/O error", EFORMAT: "malformed data",
    ECANCELLED: "cancelled", EVERSION: "unsupported version",
    ENOENT: "no such file or folder",
    EUNRECOGNISED: "not a recognised file or folder",
}


def status_string(code: int) -> str:
    """The library's short description of a status code."""
    if _status_string_fn is not None:
        return _status_string_fn(int(code)).decode("utf-8", "replace")
    return _FALLBACK_TEXT.get(int(code), "unknown status")


def error_for_status(code: int, message: str = "",
                     function: Optional[str] = None) -> NerfError:
    """Build the exception for ``code`` (a subclass when the code is known;
    the base :class:`NerfError` for codes newer than this binding)."""
    cls = _BY_STATUS.get(int(code), NerfError)
    return cls(code, message, function)


def check_status(result: int, func, args):
    """ctypes ``errcheck`` hook: raise for a negative status.

    It runs on the calling thread straight after the C call returns, so
    ``nerf_last_error()`` still holds the message of this failure.
    """
    if result < 0:
        message = ""
        if _last_error_fn is not None:
            message = _last_error_fn().decode("utf-8", "replace")
        name = getattr(func, "__name__", None)
        raise error_for_status(result, message, name)
    return result
