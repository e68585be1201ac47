"""Process-wide functions: versions, errors, logging, parameter bounds."""

from __future__ import annotations

import ctypes
from typing import Any, Callable, Optional, Tuple, Union

from . import errors
from ._capi import lib
from .structs import LOG_CB, c_int, integer

# nerf_log_level
LOG_ERROR = 0
LOG_WARN = 1
LOG_INFO = 2
LOG_DEBUG = 3

# nerf_param: training hyperparameters.
PARAM_LEARNING_RATE = 100
PARAM_LEARNING_RATE_FINAL = 101
PARAM_DECAY_STEPS = 102
PARAM_ADAM_BETA1 = 103
PARAM_ADAM_BETA2 = 104
PARAM_ADAM_EPS = 105
PARAM_WEIGHT_DECAY = 106
PARAM_DECAY_START = 107  # since libnerf 0.5
PARAM_AVERAGE_STEPS = 108  # since libnerf 0.9

#: Parameter names accepted wherever a parameter key is expected.
PARAMS = {
    "learning_rate": PARAM_LEARNING_RATE,
    "learning_rate_final": PARAM_LEARNING_RATE_FINAL,
    "decay_steps": PARAM_DECAY_STEPS,
    "adam_beta1": PARAM_ADAM_BETA1,
    "adam_beta2": PARAM_ADAM_BETA2,
    "adam_eps": PARAM_ADAM_EPS,
    "weight_decay": PARAM_WEIGHT_DECAY,
    "decay_start": PARAM_DECAY_START,
    "average_steps": PARAM_AVERAGE_STEPS,
}


def param_key(param: Union[str, int]) -> int:
    """A parameter key from its name (``"learning_rate"``) or number."""
    if isinstance(param, str):
        try:
            return PARAMS[param]
        except KeyError:
            raise ValueError("unknown parameter %r (known: %s)"
                             % (param, ", ".join(PARAMS))) from None
    return integer(param, "param", c_int)


def version() -> Tuple[int, int, int]:
    """The loaded library's version as (major, minor, patch)."""
    number = lib.nerf_version_number()
    return number // 10000, number // 100 % 100, number % 100


def version_number() -> int:
    """``nerf_version_number()``: major * 10000 + minor * 100 + patch."""
    return int(lib.nerf_version_number())


def version_string() -> str:
    """The loaded library's version, "major.minor.patch"."""
    return lib.nerf_version_string().decode()


def build_info() -> str:
    """One line on how the library was built (BLAS, libpng, ...)."""
    return lib.nerf_build_info().decode("utf-8", "replace")


def library_path() -> str:
    """The path or name the shared library was loaded from."""
    from . import _capi
    return _capi.lib.path


def status_string(code: int) -> str:
    """The library's short description of a status code."""
    return errors.status_string(code)


def last_error() -> str:
    """The calling thread's last libnerf error message ("" if none).

    The binding already puts this message into every :class:`NerfError`;
    this is for completeness.
    """
    return lib.nerf_last_error().decode("utf-8", "replace")


def clear_error() -> None:
    """Forget the calling thread's last error message."""
    lib.nerf_clear_error()


def param_bounds(param: Union[str, int]) -> Tuple[float, float]:
    """Inclusive valid range of a training parameter."""
    lo, hi = ctypes.c_double(), ctypes.c_double()
    lib.nerf_param_bounds(param_key(param), ctypes.byref(lo), ctypes.byref(hi))
    return lo.value, hi.value


# The process-wide log callback; kept here while the library holds it.
_default_log: Optional[Any] = None


def set_log_handler(handler: Optional[Callable[[int, str], Any]],
                    max_level: int = LOG_INFO) -> None:
    """Route the log lines of every handle without its own ``log=`` to
    ``handler(level, message)`` (``nerf_log_set_default``).  ``None``
    restores the library's silent default.

    Like the C function, this is process-wide and not synchronised with
    running calls: set it up before other threads use libnerf.
    """
    global _default_log
    if handler is None:
        lib.nerf_log_set_default(LOG_CB(), None, int(max_level))
        _default_log = None
        return

    def thunk(level, msg, user):
        handler(int(level), msg.decode("utf-8", "replace") if msg else "")

    cfunc = LOG_CB(thunk)
    lib.nerf_log_set_default(cfunc, None, int(max_level))
    _default_log = cfunc  # replaced only after C stopped using the old one


def log_to_stderr(max_level: int = LOG_INFO) -> None:
    """Use the library's ready-made stderr logger (``nerf_log_stderr``) as
    the process-wide log handler: lines "libnerf: <level>: <message>"."""
    global _default_log
    cfunc = LOG_CB(("nerf_log_stderr", lib.cdll))
    lib.nerf_log_set_default(cfunc, None, int(max_level))
    _default_log = cfunc


def log_stderr(level: int, message: str) -> None:
    """Write one line through the library's stderr logger."""
    lib.nerf_log_stderr(int(level), message.encode("utf-8"), None)
