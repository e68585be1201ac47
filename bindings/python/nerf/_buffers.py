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
* Lists and tuples of numbers (nested or flat), which are copied.  A
  nested sequence must be rectangular (every row as long as the first)
  and hold real numbers only: a ragged one raises ValueError, a string or
  other object in it TypeError.

Every array argument has a shape it must have, such as ``(n, 3)`` for
points.  An input of two or more dimensions (a NumPy array, a nested
sequence, a multi-dimensional memoryview) must have exactly that shape:
a 4 x 3 matrix is not taken for a 3 x 4 one, nor a (3, 4) array for
four points.  A one-dimensional input (a flat list, an ``array.array``,
a byte buffer, a 1-D array) is read as the rows one after another, and
must hold whole rows (exactly the values the shape needs when it is
fixed).  Where the library would refuse NaN or infinite values later,
they are refused here, before anything reaches C, with the
:class:`nerf.NerfInvalidArgument` (a ValueError) the library would
raise.  A wrong shape raises ValueError (TypeError for values that are
not numbers) naming the argument, the shape expected and the shape
given.

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
import math
import numbers
import os
from typing import Any, Optional, Sequence, Tuple, Union

from . import errors

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


def _nested_shape(seq: Any) -> Tuple[int, ...]:
    """The shape a nested sequence claims by its first items."""
    shape = []
    while isinstance(seq, (list, tuple)):
        shape.append(len(seq))
        if not seq:
            break
        seq = seq[0]
    return tuple(shape)


def _number(item: Any, name: str) -> float:
    # float() would take "1.5" and a one-element array as well.
    if isinstance(item, (str, bytes)) or not isinstance(item, numbers.Real):
        raise TypeError("%s: expected numbers, found a %s"
                        % (name, type(item).__name__))
    return float(item)


def _flatten(seq: Any, shape: Tuple[int, ...], depth: int, at: str,
             out: list, name: str) -> None:
    """Append the numbers of seq to out, checking that it is as
    rectangular as its first items say."""
    if len(seq) != shape[depth]:
        raise ValueError("%s: ragged nested sequence: item%s has %d "
                         "entries where item%s has %d" % (
                             name, at, len(seq),
                             "[0]" * depth if depth else "", shape[depth]))
    last = depth + 1 == len(shape)
    for i, item in enumerate(seq):
        here = "%s[%d]" % (at, i)
        if isinstance(item, (list, tuple)):
            if last:
                raise ValueError("%s: ragged nested sequence: item%s is a "
                                 "sequence where numbers are expected"
                                 % (name, here))
            _flatten(item, shape, depth + 1, here, out, name)
        elif not last:
            raise ValueError("%s: ragged nested sequence: item%s is a "
                             "number where a sequence is expected"
                             % (name, here))
        else:
            out.append(_number(item, name))


def _from_array_f(values: "array.array", shape: Tuple[int, ...],
                  copied: bool, keep: Any = None) -> FloatInput:
    n = len(values)
    if n == 0:
        return FloatInput(None, 0, shape, copied, values)
    carr = (ctypes.c_float * n).from_buffer(values)
    return FloatInput(ctypes.cast(carr, _FLOAT_P), n, shape, copied,
                      (values, carr, keep))


#: A shape an argument must have: ints, and None for a free dimension
#: (``(None, 3)``: n x 3).  A list of them gives the shapes allowed.
Shape = Union[Tuple[Optional[int], ...], Sequence[Tuple[Optional[int], ...]]]


def as_float_input(obj: Any, name: str = "array", shape: Shape = None,
                   finite: bool = False) -> FloatInput:
    """Make ``obj`` readable by C as contiguous float32 data.

    ``shape``: the shape ``obj`` must have (see the module's docstring);
    the result's ``shape`` is then the matching one, free dimensions
    resolved.  ``finite``: refuse NaN and infinite values (after the
    conversion to float32, so 1e39 counts as infinite).

    Raises:
        TypeError: ``obj`` is not an array, buffer or sequence of numbers.
        ValueError: ``obj`` is ragged, has another shape, or (``finite``)
            holds a NaN or infinite value.
    """
    buf = _as_float(obj, name)
    if shape is not None:
        buf.shape = match_shape(buf.shape, shape, name)
    if finite:
        _check_finite(buf, name)
    return buf


def _shape_text(shape: Sequence[Optional[int]]) -> str:
    dims = ["n" if d is None else str(d) for d in shape]
    return "(%s)" % (dims[0] + "," if len(dims) == 1 else ", ".join(dims))


def _match_one(got: Tuple[int, ...],
               want: Tuple[Optional[int], ...]) -> Optional[Tuple[int, ...]]:
    if len(got) == len(want):
        if all(w is None or w == g for g, w in zip(got, want)):
            return got
        return None
    free = [i for i, w in enumerate(want) if w is None]
    if len(got) != 1 or len(free) > 1:
        return None
    # A flat input holds the rows one after another.
    row = 1
    for w in want:
        row *= 1 if w is None else w
    if not free:
        return tuple(want) if got[0] == row else None
    if row == 0 or got[0] % row:
        return None
    out = list(want)
    out[free[0]] = got[0] // row
    return tuple(out)


def match_shape(got: Tuple[int, ...], want: Shape,
                name: str) -> Tuple[int, ...]:
    """The shape of ``want`` (one shape or a list of them) that ``got``
    fits, free dimensions resolved; ValueError naming both otherwise."""
    options = list(want) if want and isinstance(want[0], (tuple, list)) \
        else [tuple(want)]
    for option in options:
        found = _match_one(tuple(got), tuple(option))
        if found is not None:
            return found
    raise ValueError("%s: expected shape %s, got %s" % (
        name, " or ".join(_shape_text(o) for o in options),
        _shape_text(got)))


def _check_finite(buf: FloatInput, name: str) -> None:
    if buf.size == 0:
        return
    carr = (ctypes.c_float * buf.size).from_address(
        ctypes.addressof(buf.ptr.contents))
    if np is not None:
        ok = np.isfinite(np.frombuffer(carr, dtype=np.float32))
        if ok.all():
            return
        first = int(np.argmin(ok))
    else:
        values = memoryview(carr).cast("B").cast("f")
        # In double a sum of float32 values overflows only past 10^270
        # of them: it is finite exactly when they all are.
        if math.isfinite(sum(values)):
            return
        first = next(i for i, v in enumerate(values) if not math.isfinite(v))
    # What the library would raise for it, a ValueError too.
    raise errors.NerfInvalidArgument(
        errors.EINVAL, "%s: value %d of %d is %s: NaN and infinite values "
        "are refused here" % (name, first, buf.size, carr[first]))


_NUMERIC_KINDS = "iuf"


def _as_float(obj: Any, name: str) -> FloatInput:
    if np is not None and isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _NUMERIC_KINDS:
            raise TypeError("%s: expected an array of real numbers, not of "
                            "dtype %s" % (name, obj.dtype))
        arr = obj
        copied = False
        if (arr.dtype != np.float32 or not arr.flags.c_contiguous or
                not arr.flags.aligned):
            arr = np.array(arr, dtype=np.float32, order="C", copy=True)
            copied = True
        return FloatInput(arr.ctypes.data_as(_FLOAT_P), int(arr.size),
                          tuple(arr.shape), copied, arr)
    if isinstance(obj, (list, tuple)):
        shape = _nested_shape(obj)
        flat: list = []
        _flatten(obj, shape, 0, "", flat, name)
        return _from_array_f(array.array("f", flat), shape, True)
    if isinstance(obj, str):
        raise TypeError("%s: expected numbers, not a str" % name)
    try:
        view = memoryview(obj)
    except TypeError:
        if np is not None and not isinstance(obj, (str, dict, set)):
            # Anything NumPy understands (scalars, objects with __array__).
            try:
                arr = np.asarray(obj)
            except (TypeError, ValueError) as err:
                raise TypeError("%s: not an array of numbers: %s"
                                % (name, err)) from None
            if arr.dtype.kind in _NUMERIC_KINDS:
                return _as_float(arr, name)
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


def as_uint8_input(obj: Any, name: str = "array"
                   ) -> Tuple[Any, int, Any, Tuple[int, ...]]:
    """Return (``POINTER(c_uint8)``, byte count, keep-alive, shape) for
    8-bit data (a byte string's shape is its length)."""
    if np is not None and isinstance(obj, np.ndarray):
        arr = np.ascontiguousarray(obj, dtype=np.uint8)
        return (arr.ctypes.data_as(_UINT8_P), int(arr.size), arr,
                tuple(arr.shape))
    view = memoryview(obj)
    shape = tuple(view.shape) if view.ndim else (view.nbytes,)
    if not view.c_contiguous or view.readonly:
        view = memoryview(bytearray(view.tobytes()))
    view = view.cast("B")
    carr = (ctypes.c_uint8 * view.nbytes).from_buffer(view)
    return ctypes.cast(carr, _UINT8_P), view.nbytes, (view, carr), shape


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


def _bytes_text(n: int) -> str:
    for unit, scale in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= scale:
            return "%.1f %s" % (n / scale, unit)
    return "%d bytes" % n


def output_bytes(shape: Sequence[int], itemsize: int = 4) -> int:
    """Bytes of an output array of this shape."""
    n = itemsize
    for s in shape:
        n *= int(s)
    return n


def _allocate(make: Any, shape: Tuple[int, ...], itemsize: int,
              name: str) -> Any:
    try:
        return make()
    except (MemoryError, OverflowError, ValueError):
        # NumPy says ValueError, and bytes() OverflowError, for a size
        # beyond the address space: no less a failed allocation.
        raise MemoryError("%s: cannot allocate %s for an array of shape %s"
                          % (name, _bytes_text(output_bytes(shape, itemsize)),
                             _shape_text(shape))) from None


class FloatOutput:
    """A new float32 array for C to fill: pass ``ptr``, return ``value``.
    A failed allocation raises MemoryError naming ``name`` and the size."""

    __slots__ = ("value", "ptr", "size", "_keep")

    def __init__(self, shape: Sequence[int], name: str = "output") -> None:
        shape = tuple(int(s) for s in shape)
        n = 1
        for s in shape:
            n *= s
        self.size = n
        if np is not None:
            arr = _allocate(lambda: np.empty(shape, dtype=np.float32), shape,
                            4, name)
            self.value = arr
            self.ptr = arr.ctypes.data_as(_FLOAT_P)
            self._keep = arr
        else:
            store = _allocate(lambda: array.array("f", bytes(4 * n)), shape,
                              4, name)
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

    def __init__(self, shape: Sequence[int], name: str = "output") -> None:
        shape = tuple(int(s) for s in shape)
        n = 1
        for s in shape:
            n *= s
        if np is not None:
            arr = _allocate(lambda: np.empty(shape, dtype=np.uint8), shape, 1,
                            name)
            self.value = arr
            self.ptr = arr.ctypes.data_as(_UINT8_P)
            self._keep = arr
        else:
            store = _allocate(lambda: bytearray(n), shape, 1, name)
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


def borrowed_bytes(address: int, shape: Sequence[int], owner: Any) -> Any:
    """:func:`borrowed_floats` for 8-bit data, always read-only."""
    n = 1
    for s in shape:
        n *= int(s)
    carr = (ctypes.c_uint8 * n).from_address(address)
    carr._nerf_owner = owner  # the array's lifetime pins the owner
    if np is not None:
        arr = np.frombuffer(carr, dtype=np.uint8).reshape(tuple(shape))
        arr.flags.writeable = False
        return arr
    return memoryview(carr).cast("B").cast("B", tuple(shape)).toreadonly()
