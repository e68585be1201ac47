"""Moving arrays between Python and libnerf, with or without NumPy.

Inputs (positions, images, ...) may be:

* NumPy arrays.  A C-contiguous, aligned ``float32`` array is passed to the
  library without copying.  Any other array is converted with
  ``numpy.array(a, dtype=numpy.float32, order="C")``, which copies.
* Any other object with the buffer protocol.  A contiguous buffer of
  format ``'f'`` (``array.array('f')``, a ``memoryview`` cast to ``'f'``)
  is passed without copying when it is writable and copied when it is
  read-only.  A byte buffer (``bytearray``, ``bytes``, format ``'B'``) is
  taken as raw native-endian float32 data, copied only when read-only or
  misaligned.  Other numeric formats (``'d'``, ``'i'``, ...) are converted,
  which copies.
* Lists and tuples of numbers (nested or flat), which are copied.

Outputs are NumPy ``float32`` (or ``uint8``) arrays when NumPy is available
and ``memoryview`` objects of format ``'f'`` (or ``'B'``) with the same
shape otherwise; the memory behind such a view is an ``array.array``
(``view.obj``).  Either way the library writes straight into them.

Setting the environment variable ``NERF_PY_NO_NUMPY=1`` before importing
``nerf`` makes the package behave as if NumPy were not installed.
"""

from __future__ import annotations

import array
import ctypes
import os
from typing import Any, Optional, Sequence, Tuple

if os.environ.get("NERF_PY_NO_NUMPY", "") not in ("", "0"):
    np = None
else:
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - depends on the installation
        np = None

#: True when NumPy is in use.
HAVE_NUMPY = np is not None

_FLOAT_P = ctypes.POINTER(ctypes.c_float)
_UINT8_P = ctypes.POINTER(ctypes.c_uint8)
# Formats of 4-byte native floats (the C float of every supported platform).
_FLOAT_FORMATS = ("f", "<f", "=f", "@f")
_BYTE_FORMATS = ("B", "b", "c", "<B", "=B", "@B")


class FloatInput:
    """A float32 buffer ready for C: ``ptr`` stays valid while this lives.

    Attributes:
        ptr: ``POINTER(c_float)`` to the first element.
        size: number of floats.
        shape: the input's shape when it had one (NumPy or memoryview),
            else ``(size,)``.
        copied: whether the data had to be copied.
    """

    __slots__ = ("ptr", "size", "shape", "copied", "_keep")

    def __init__(self, ptr, size: int, shape: Tuple[int, ...], copied: bool,
                 keep: Any) -> None:
        self.ptr = ptr
        self.size = size
        self.shape = shape
        self.copied = copied
        self._keep = keep


def _flatten(seq: Any, out: list) -> None:
    for item in seq:
        if isinstance(item, (list, tuple)):
            _flatten(item, out)
        else:
            out.append(float(item))


def _nested_shape(seq: Any) -> Tuple[int, ...]:
    shape = []
    while isinstance(seq, (list, tuple)):
        shape.append(len(seq))
        if not seq:
            break
        seq = seq[0]
    return tuple(shape)


def _from_array_f(values: "array.array", shape: Tuple[int, ...],
                  copied: bool, keep: Any = None) -> FloatInput:
    n = len(values)
    if n == 0:
        return FloatInput(None, 0, shape, copied, values)
    carr = (ctypes.c_float * n).from_buffer(values)
    return FloatInput(ctypes.cast(carr, _FLOAT_P), n, shape, copied,
                      (values, carr, keep))


def as_float_input(obj: Any, name: str = "array") -> FloatInput:
    """Make ``obj`` readable by C as contiguous float32 data.

    Raises:
        TypeError: ``obj`` is not an array, buffer or sequence of numbers.
    """
    if np is not None and isinstance(obj, np.ndarray):
        arr = obj
        copied = False
        if (arr.dtype != np.float32 or not arr.flags.c_contiguous or
                not arr.flags.aligned):
            arr = np.array(arr, dtype=np.float32, order="C", copy=True)
            copied = True
        return FloatInput(arr.ctypes.data_as(_FLOAT_P), int(arr.size),
                          tuple(arr.shape), copied, arr)
    if isinstance(obj, (list, tuple)):
        flat: list = []
        _flatten(obj, flat)
        return _from_array_f(array.array("f", flat), _nested_shape(obj), True)
    try:
        view = memoryview(obj)
    except TypeError:
        if np is not None:
            # Anything NumPy understands (scalars, objects with __array__).
            return as_float_input(np.asarray(obj, dtype=np.float32), name)
        raise TypeError("%s: expected a float32 array, a buffer or a "
                        "sequence of numbers, not %s"
                        % (name, type(obj).__name__)) from None
    return _from_view(view, name)


def _from_view(view: memoryview, name: str) -> FloatInput:
    shape = tuple(view.shape or (view.nbytes // max(view.itemsize, 1),))
    if not view.c_contiguous:
        # Gather into a fresh contiguous buffer first (a copy).
        view = memoryview(view.tobytes()).cast("B").cast(view.format)
    fmt = view.format
    if fmt in _FLOAT_FORMATS or fmt in _BYTE_FORMATS:
        if fmt in _BYTE_FORMATS:
            if view.nbytes % 4:
                raise ValueError("%s: a byte buffer holding float32 data "
                                 "must have a multiple of 4 bytes, not %d"
                                 % (name, view.nbytes))
            shape = (view.nbytes // 4,)
        n = view.nbytes // 4
        if n == 0:
            return FloatInput(None, 0, shape, False, view)
        if not view.readonly:
            carr = (ctypes.c_float * n).from_buffer(view)
            if ctypes.addressof(carr) % ctypes.alignment(ctypes.c_float) == 0:
                return FloatInput(ctypes.cast(carr, _FLOAT_P), n, shape,
                                  False, (view, carr))
            del carr
        carr = (ctypes.c_float * n).from_buffer_copy(view)
        return FloatInput(ctypes.cast(carr, _FLOAT_P), n, shape, True, carr)
    try:
        flat = view.cast("B").cast(fmt.lstrip("<=@")).tolist()
    except (TypeError, ValueError) as err:
        raise TypeError("%s: cannot read buffer of format %r as float32: %s"
                        % (name, fmt, err)) from None
    return _from_array_f(array.array("f", [float(v) for v in flat]), shape,
                         True)


def as_uint8_input(obj: Any, name: str = "array") -> Tuple[Any, int, Any]:
    """Return (``POINTER(c_uint8)``, byte count, keep-alive) for 8-bit data."""
    if np is not None and isinstance(obj, np.ndarray):
        arr = np.ascontiguousarray(obj, dtype=np.uint8)
        return arr.ctypes.data_as(_UINT8_P), int(arr.size), arr
    view = memoryview(obj)
    if not view.c_contiguous or view.readonly:
        view = memoryview(bytearray(view.tobytes()))
    view = view.cast("B")
    carr = (ctypes.c_uint8 * view.nbytes).from_buffer(view)
    return ctypes.cast(carr, _UINT8_P), view.nbytes, (view, carr)


def is_uint8(obj: Any) -> bool:
    """Whether ``obj`` holds 8-bit samples (a uint8 array or byte buffer)."""
    if np is not None and isinstance(obj, np.ndarray):
        return obj.dtype == np.uint8
    if isinstance(obj, (bytes, bytearray)):
        return True
    try:
        return memoryview(obj).format in _BYTE_FORMATS
    except TypeError:
        return False


def array_shape(obj: Any) -> Optional[Tuple[int, ...]]:
    """The shape of a NumPy array, memoryview or nested sequence, or None."""
    if np is not None and isinstance(obj, np.ndarray):
        return tuple(obj.shape)
    if isinstance(obj, memoryview):
        return tuple(obj.shape)
    if isinstance(obj, (list, tuple)):
        return _nested_shape(obj)
    return None


class FloatOutput:
    """A new float32 array for C to fill: pass ``ptr``, return ``value``."""

    __slots__ = ("value", "ptr", "size", "_keep")

    def __init__(self, shape: Sequence[int]) -> None:
        shape = tuple(int(s) for s in shape)
        n = 1
        for s in shape:
            n *= s
        self.size = n
        if np is not None:
            arr = np.empty(shape, dtype=np.float32)
            self.value = arr
            self.ptr = arr.ctypes.data_as(_FLOAT_P)
            self._keep = arr
        else:
            store = array.array("f", bytes(4 * n))
            carr = (ctypes.c_float * n).from_buffer(store) if n else None
            self.ptr = ctypes.cast(carr, _FLOAT_P) if n else None
            self._keep = carr
            self.value = memoryview(store).cast("B").cast("f", shape) \
                if n else memoryview(store)

    def release(self) -> Any:
        """Drop the C view and return the array."""
        self._keep = None
        self.ptr = None
        return self.value


class Uint8Output:
    """A new uint8 array for C to fill."""

    __slots__ = ("value", "ptr", "_keep")

    def __init__(self, shape: Sequence[int]) -> None:
        shape = tuple(int(s) for s in shape)
        n = 1
        for s in shape:
            n *= s
        if np is not None:
            arr = np.empty(shape, dtype=np.uint8)
            self.value = arr
            self.ptr = arr.ctypes.data_as(_UINT8_P)
            self._keep = arr
        else:
            store = bytearray(n)
            carr = (ctypes.c_uint8 * n).from_buffer(store)
            self.ptr = ctypes.cast(carr, _UINT8_P)
            self._keep = carr
            self.value = memoryview(store).cast("B", shape)

    def release(self) -> Any:
        """Drop the C view and return the array."""
        self._keep = None
        self.ptr = None
        return self.value


def borrowed_floats(address: int, shape: Sequence[int], owner: Any,
                    readonly: bool = True) -> Any:
    """Wrap C memory as an array without copying.

    ``owner`` is attached to the wrapper and lives as long as the returned
    array (or any view of it): it must keep the memory valid, for example
    by holding the handle that owns it or by freeing it when collected.
    """
    n = 1
    for s in shape:
        n *= int(s)
    carr = (ctypes.c_float * n).from_address(address)
    carr._nerf_owner = owner  # the array's lifetime pins the owner
    if np is not None:
        arr = np.frombuffer(carr, dtype=np.float32).reshape(tuple(shape))
        if readonly:
            arr.flags.writeable = False
        return arr
    view = memoryview(carr).cast("B").cast("f", tuple(shape))
    return view.toreadonly() if readonly else view
