"""ctypes mirrors of the public structs of ``nerf.h``.

Each options struct is a :class:`ctypes.Structure` whose constructor calls
the library's own ``*_init`` function with ``ctypes.sizeof`` of the mirror,
so defaults always come from the library, never from this file.  Keyword
arguments then override single fields::

    opts = nerf.SamplerOptions(n_coarse=16, n_fine=0)

The field lists must match the C declarations exactly; the test
``tests/test_layout.py`` compares every size and offset with a C probe.
Fields are only ever appended in C, so a mirror that is shorter than the
library's struct still works (the library uses defaults for the rest).
"""

from __future__ import annotations

import ctypes
import math
import operator
import os
from ctypes import (POINTER, c_char_p, c_double, c_float, c_int, c_int32,
                    c_size_t, c_uint32, c_uint64, c_void_p)
from dataclasses import dataclass
from typing import Any, Dict, Sequence, Tuple

from . import _buffers, errors

# Callback types (nerf_log_cb, nerf_progress_cb and the allocator hooks).
LOG_CB = ctypes.CFUNCTYPE(None, c_int, c_char_p, c_void_p)
ALLOC_FN = ctypes.CFUNCTYPE(c_void_p, c_size_t, c_void_p)
FREE_FN = ctypes.CFUNCTYPE(None, c_void_p, c_void_p)


def _capi():
    # Imported lazily: _capi needs these classes for its prototypes.
    from . import _capi as capi
    return capi.lib


def _int_range(ctype: Any) -> Tuple[int, int]:
    bits = 8 * ctypes.sizeof(ctype)
    if ctype(-1).value < 0:
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return 0, (1 << bits) - 1


def integer(value: Any, name: str, ctype: Any = c_uint32) -> int:
    """``value`` as an int that the C integer type ``ctype`` holds exactly.

    ctypes wraps silently (-1 becomes 4294967295 in a uint32), so every
    integer the binding hands to C, struct field or argument, comes through
    here.

    Raises:
        TypeError: ``value`` is not an integer (a float, a str, ...).
        ValueError: ``value`` is out of ``ctype``'s range.
    """
    try:
        v = operator.index(value)
    except TypeError:
        raise TypeError("%s: expected an integer, not %s"
                        % (name, type(value).__name__)) from None
    lo, hi = _int_range(ctype)
    if not lo <= v <= hi:
        raise ValueError("%s: %d is out of range: %s" % (
            name, v, "0 to %d" % hi if lo == 0 else "%d to %d" % (lo, hi)))
    return v


class _Versioned(ctypes.Structure):
    """Base of the size-prefixed structs; see the module docstring."""

    #: Name of the C struct (checked by the layout test).
    _c_name_ = ""
    #: Name of the C function filling the defaults, or "" if there is none.
    _c_init_ = ""
    #: Fields a caller should not set by keyword.
    _private_ = ("struct_size", "hooks")

    def __init__(self, **fields: Any) -> None:
        super().__init__()
        if self._c_init_:
            init = getattr(_capi(), self._c_init_)
            init(ctypes.byref(self), ctypes.sizeof(self))
        else:
            self.struct_size = ctypes.sizeof(self)
        self.update(**fields)

    @classmethod
    def field_names(cls) -> Tuple[str, ...]:
        """Names of the fields a caller may set."""
        return tuple(name for name, *_ in cls._fields_
                     if name not in cls._private_ and
                     not name.startswith("reserved"))

    def update(self, **fields: Any) -> "_Versioned":
        """Set fields by name; unknown names raise TypeError."""
        allowed = self.field_names()
        for name, value in fields.items():
            if name not in allowed:
                raise TypeError("%s has no settable field %r (fields: %s)"
                                % (type(self).__name__, name,
                                   ", ".join(allowed)))
            self._set(name, value)
        return self

    def _set(self, name: str, value: Any) -> None:
        setattr(self, name, value)

    def to_dict(self) -> Dict[str, Any]:
        """The settable fields as a dict."""
        return {name: self._get(name) for name in self.field_names()}

    def _get(self, name: str) -> Any:
        return getattr(self, name)

    def copy(self):
        """An independent copy (the struct's bytes, hooks included)."""
        return type(self).from_buffer_copy(self)

    def __repr__(self) -> str:
        body = ", ".join("%s=%r" % kv for kv in self.to_dict().items())
        return "%s(%s)" % (type(self).__name__, body)


class Hooks(_Versioned):
    """``nerf_hooks``: allocation and logging of one handle.

    The binding fills this itself when a handle is created with ``log=``;
    it is exposed for completeness.  Allocator hooks written in Python are
    possible but slow, and the library may call them from worker threads.
    """

    _c_name_ = "nerf_hooks"
    _c_init_ = "nerf_hooks_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("log_level", c_int32),
        ("alloc", ALLOC_FN),
        ("free", FREE_FN),
        ("alloc_user", c_void_p),
        ("log_cb", LOG_CB),
        ("log_user", c_void_p),
    ]


class ProgressStruct(_Versioned):
    """``nerf_progress``, as the library passes it to progress callbacks."""

    _c_name_ = "nerf_progress"
    _fields_ = [
        ("struct_size", c_uint32),
        ("kind", c_uint32),
        ("done", c_uint64),
        ("total", c_uint64),
        ("elapsed", c_double),
        ("loss", c_double),
        ("psnr", c_double),
    ]


#: Longest list of sparse ranges in a nerf_exchange.
EXCHANGE_MAX_SPARSE = 4


class ExchangeStruct(_Versioned):
    """``nerf_exchange``, as a trainer passes it to its gradient and
    checksum hooks (since libnerf 0.5)."""

    _c_name_ = "nerf_exchange"
    _fields_ = [
        ("struct_size", c_uint32),
        ("worker_rank", c_uint32),
        ("worker_count", c_uint32),
        ("n_sparse", c_uint32),
        ("step", c_uint64),
        ("sparse_begin", c_uint64 * EXCHANGE_MAX_SPARSE),
        ("sparse_end", c_uint64 * EXCHANGE_MAX_SPARSE),
        ("rays", c_uint64),
        ("batch_rays", c_uint64),
        ("message", ctypes.c_char * 256),
    ]


# nerf_progress_cb and the trainer's hooks, as the C structs hold them.
PROGRESS_CB = ctypes.CFUNCTYPE(c_int, POINTER(ProgressStruct), c_void_p)
GRAD_HOOK = ctypes.CFUNCTYPE(c_int, c_void_p, POINTER(c_float), c_size_t,
                             POINTER(ExchangeStruct))
CHECKSUM_HOOK = ctypes.CFUNCTYPE(c_int, c_void_p, POINTER(c_uint32),
                                 POINTER(ExchangeStruct))


class ModelOptions(_Versioned):
    """``nerf_model_options``: structural settings of a model.

    The enum fields (``encoding``, ``encoding_flags``, ``dir_encoding``,
    ``density_activation``, ``matmul``, ``space``) read as
    :class:`Named` values, ints shown by name (``encoding='hashgrid'``),
    and may be set by name or number.
    """

    _c_name_ = "nerf_model_options"
    _c_init_ = "nerf_model_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("encoding", c_uint32),
        ("pos_frequencies", c_uint32),
        ("dir_frequencies", c_uint32),
        ("encoding_flags", c_uint32),
        ("depth", c_uint32),
        ("width", c_uint32),
        ("skip_layer", c_uint32),
        ("view_width", c_uint32),
        ("use_viewdirs", c_uint32),
        ("use_fine", c_uint32),
        ("reserved0", c_uint32),
        ("seed", c_uint64),
        ("hooks", POINTER(Hooks)),
        # Appended in libnerf 0.2.
        ("dir_encoding", c_uint32),
        ("sh_degree", c_uint32),
        ("hash_levels", c_uint32),
        ("hash_features", c_uint32),
        ("hash_log2_size", c_uint32),
        ("hash_min_resolution", c_uint32),
        ("hash_max_resolution", c_uint32),
        ("bound", c_float),
        ("geo_features", c_uint32),
        ("view_depth", c_uint32),
        ("density_activation", c_uint32),
        # nerf_matmul; formerly reserved1 (0 = fp32).
        ("matmul", c_uint32),
        # Appended in libnerf 0.3: nerf_space (0 = BOX).
        ("space", c_uint32),
        # Appended in libnerf 0.12: 0 = the model kind's rate.
        ("reserved2", c_uint32),
        ("learning_rate", c_double),
    ]


class Named(int):
    """The value of an enum field of an options struct (``encoding``,
    ``matmul``, ``space``, ...): the int the C API takes, shown by name.

    ``repr`` and ``str`` give the name (``'hashgrid'``), ``.name`` too;
    it compares equal to its int and to its name, and hashes as its int.
    """

    #: The names of the values, in C's order (a later name of one value
    #: is what a name maps back to).
    _names: Dict[int, str] = {}
    #: Whether the value is a set of bit flags, shown joined with ``|``.
    _flags = False

    @property
    def name(self) -> str:
        value = int(self)
        if not self._flags:
            return self._names.get(value, str(value))
        parts = [n for bit, n in self._names.items() if value & bit]
        rest = value & ~sum(self._names)
        if rest:
            parts.append(hex(rest))
        return "|".join(parts) if parts else "none"

    def __repr__(self) -> str:
        return repr(self.name)

    def __str__(self) -> str:
        return self.name

    def __eq__(self, other: Any) -> bool:
        if isinstance(other, str):
            try:
                return int(self) == self.key(other)
            except ValueError:
                return False
        return int(self) == other

    def __ne__(self, other: Any) -> bool:
        return not self.__eq__(other)

    __hash__ = int.__hash__

    @classmethod
    def key(cls, value: Any) -> int:
        """The int of a name (or of an int); ValueError names the known
        ones."""
        if not isinstance(value, str):
            return integer(value, cls.__name__)
        by_name = {n: v for v, n in cls._names.items()}
        parts = value.split("|") if cls._flags else [value]
        total = 0
        for part in parts:
            if cls._flags and part == "none":
                continue
            if part not in by_name:
                raise ValueError("unknown %s %r (known: %s)"
                                 % (cls.__name__, part,
                                    ", ".join(sorted(set(by_name)))))
            total |= by_name[part]
        return total


class Encoding(Named):
    """``nerf_encoding_kind``."""
    _names = {1: "frequency", 2: "hashgrid", 3: "spherical_harmonics"}


class DirEncoding(Named):
    """``nerf_encoding_kind`` of ``dir_encoding``, where 0 reads as
    frequency."""
    _names = {0: "frequency", 1: "frequency", 2: "hashgrid",
              3: "spherical_harmonics"}


class EncodingFlags(Named):
    """``NERF_ENCODING_*`` flags."""
    _names = {1: "include_input", 2: "scale_pi"}
    _flags = True


class DensityActivation(Named):
    """``nerf_density_activation``."""
    _names = {0: "relu", 1: "exp"}


class Matmul(Named):
    """``nerf_matmul``."""
    _names = {0: "fp32", 1: "bf16", 2: "fp32-onednn", 3: "fp32-fastest"}


class Space(Named):
    """``nerf_space``."""
    _names = {0: "box", 1: "ndc", 2: "unbounded"}


class _IntField:
    """An integer struct field that refuses what its C type cannot hold
    (see :func:`integer`) instead of wrapping it; ``offset`` and ``size``
    are the ctypes field's."""

    def __init__(self, raw: Any, name: str, ctype: Any) -> None:
        self._raw = raw
        self._name = name
        self._ctype = ctype

    offset = property(lambda self: self._raw.offset)
    size = property(lambda self: self._raw.size)

    def __get__(self, obj: Any, objtype: Any = None) -> Any:
        if obj is None:
            return self
        return self._raw.__get__(obj, objtype)

    def __set__(self, obj: Any, value: Any) -> None:
        what = "%s.%s" % (type(obj).__name__, self._name)
        self._raw.__set__(obj, integer(value, what, self._ctype))


class _NamedField:
    """A struct field read as a :class:`Named` and set by name or int;
    ``offset`` and ``size`` are the ctypes field's."""

    def __init__(self, raw: Any, kind: type) -> None:
        self._raw = raw
        self._kind = kind

    offset = property(lambda self: self._raw.offset)
    size = property(lambda self: self._raw.size)

    def __get__(self, obj: Any, objtype: Any = None) -> Any:
        if obj is None:
            return self
        return self._kind(self._raw.__get__(obj, objtype))

    def __set__(self, obj: Any, value: Any) -> None:
        if isinstance(value, str):
            value = self._kind.key(value)
        self._raw.__set__(obj, value)


class _PathField(_IntField):
    """A path (``char *``) field: set from a str, bytes or os.PathLike
    through the binding's one path converter (a NUL would cut it)."""

    def __set__(self, obj: Any, value: Any) -> None:
        if value is not None:
            from ._handle import fspath  # _handle imports this module
            value = fspath(value, "%s.%s" % (type(obj).__name__, self._name))
        self._raw.__set__(obj, value)


_INTEGER_CODES = "bBhHiIlLqQ"


def _check_fields(cls: type) -> None:
    """Route every integer field of ``cls`` through :func:`integer`, and
    every path field through the path converter."""
    for name, ctype, *_ in cls._fields_:
        if ctype is c_char_p:
            setattr(cls, name, _PathField(cls.__dict__[name], name, ctype))
        elif (isinstance(ctype, type) and
                issubclass(ctype, ctypes._SimpleCData) and
                ctype._type_ in _INTEGER_CODES):
            setattr(cls, name, _IntField(cls.__dict__[name], name, ctype))


def _name_fields(cls: type, kinds: Dict[str, type]) -> None:
    for name, kind in kinds.items():
        setattr(cls, name, _NamedField(cls.__dict__[name], kind))


class SceneOptions(_Versioned):
    """``nerf_scene_options``: what :func:`nerf.write_scene` produces."""

    _c_name_ = "nerf_scene_options"
    _c_init_ = "nerf_scene_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("width", c_uint32),
        ("height", c_uint32),
        ("n_train", c_uint32),
        ("n_val", c_uint32),
        ("n_test", c_uint32),
        ("threads", c_uint32),
        # Formerly reserved0 (0 = constant); libnerf 0.13.
        ("appearance", c_uint32),
        ("seed", c_uint64),
        ("hooks", POINTER(Hooks)),
        ("capture", c_uint32),
        ("layout", c_uint32),
        ("image_format", c_uint32),
        ("jpeg_quality", c_uint32),
        ("k1", c_float),
        ("k2", c_float),
        ("p1", c_float),
        ("p2", c_float),
        ("k3", c_float),
        ("occluders", c_uint32),
        ("texture", c_uint32),
        ("reserved1", c_uint32),
    ]


class SamplerOptions(_Versioned):
    """``nerf_sampler_options``: sample placement along rays."""

    _c_name_ = "nerf_sampler_options"
    _c_init_ = "nerf_sampler_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("n_coarse", c_uint32),
        ("n_fine", c_uint32),
        ("perturb", c_uint32),
        ("lindisp", c_uint32),
        ("paper_bins", c_uint32),
        ("ndc", c_uint32),
        ("reserved0", c_uint32),
        ("t_near", c_float),
        ("t_far", c_float),
        ("ndc_focal", c_float),
        ("ndc_width", c_uint32),
        ("ndc_height", c_uint32),
        ("reserved1", c_uint32),
        ("seed", c_uint64),
        ("hooks", POINTER(Hooks)),
        # Appended in libnerf 0.2.
        ("march_steps", c_uint32),
        ("max_samples", c_uint32),
    ]


class RendererOptions(_Versioned):
    """``nerf_renderer_options``: settings of a renderer."""

    _c_name_ = "nerf_renderer_options"
    _c_init_ = "nerf_renderer_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("white_background", c_uint32),
        ("raw_noise_std", c_float),
        ("chunk_rays", c_uint32),
        ("threads", c_uint32),
        # Formerly reserved0 (0 = the neutral appearance); libnerf 0.13.
        ("appearance", c_uint32),
        ("hooks", POINTER(Hooks)),
    ]


class PointsOptions(_Versioned):
    """``nerf_points_options`` (libnerf 0.5): how rendered views become a
    point cloud (see :meth:`nerf.Renderer.points`)."""

    _c_name_ = "nerf_points_options"
    _c_init_ = "nerf_points_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("opacity_threshold", c_float),
        ("max_points", c_uint64),
        ("stride", c_uint32),
        ("reserved0", c_uint32),
        ("hooks", POINTER(Hooks)),
        # The binding sets it to its progress thunk.
        ("progress", PROGRESS_CB),
        ("progress_user", c_void_p),
    ]

class BakeOptions(_Versioned):
    """``nerf_bake_options`` (since libnerf 0.14): the voxels, colours and
    memory of :class:`nerf.Bake`."""

    _c_name_ = "nerf_bake_options"
    _c_init_ = "nerf_bake_options_init"
    _private_ = ("struct_size", "hooks", "progress", "progress_user")
    _fields_ = [
        ("struct_size", c_uint32),
        ("subdivisions", c_uint32),
        ("sh_degree", c_uint32),
        ("directions", c_uint32),
        ("max_bytes", ctypes.c_uint64),
        ("march_steps", c_uint32),
        ("appearance", c_uint32),
        ("progress", PROGRESS_CB),
        ("progress_user", c_void_p),
        ("hooks", POINTER(Hooks)),
    ]


class BakeStats(_Versioned):
    """``nerf_bake_stats`` (since libnerf 0.14), filled by
    :attr:`nerf.Bake.stats`."""

    _c_name_ = "nerf_bake_stats"
    _fields_ = [
        ("struct_size", c_uint32),
        ("resolution", c_uint32),
        ("bricks", ctypes.c_uint64),
        ("points", ctypes.c_uint64),
        ("bytes", ctypes.c_uint64),
    ]


class MeshOptions(_Versioned):
    """``nerf_mesh_options`` (since libnerf 0.5): the grid, threshold and
    filters of :meth:`nerf.Model.mesh` and
    :meth:`nerf.Model.write_density_grid`."""

    _c_name_ = "nerf_mesh_options"
    _c_init_ = "nerf_mesh_options_init"
    _private_ = ("struct_size", "hooks", "progress", "progress_user")
    _fields_ = [
        ("struct_size", c_uint32),
        ("resolution", c_uint32),
        ("threshold", c_float),
        ("box", c_float * 6),
        ("colour", c_uint32),
        ("keep_largest", c_uint32),
        ("min_component_faces", c_uint32),
        ("threads", c_uint32),
        ("reserved0", c_uint32),
        ("progress", PROGRESS_CB),
        ("progress_user", c_void_p),
        ("hooks", POINTER(Hooks)),
    ]

    def _set(self, name: str, value: Any) -> None:
        if name == "box":
            # x0 y0 z0 x1 y1 z1; the library refuses a box not finite.
            buf = _buffers.as_float_input(value, "box", shape=(6,),
                                          finite=True)
            ctypes.memmove(self.box, buf.ptr, 6 * 4)
            return
        setattr(self, name, value)

    def _get(self, name: str) -> Any:
        if name == "box":
            return tuple(self.box)
        return getattr(self, name)


class CameraPathOptions(_Versioned):
    """``nerf_camera_path_options``: how a camera path file becomes
    cameras (see :func:`nerf.load_camera_path`)."""

    _c_name_ = "nerf_camera_path_options"
    _c_init_ = "nerf_camera_path_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("width", c_uint32),
        ("height", c_uint32),
        ("flags", c_uint32),
        ("focal", c_float),
        ("fov_x", c_float),
        ("hooks", POINTER(Hooks)),
    ]


class DatasetOptions(_Versioned):
    """``nerf_dataset_options``: how a dataset is read."""

    _c_name_ = "nerf_dataset_options"
    _c_init_ = "nerf_dataset_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("split", c_uint32),
        ("downscale", c_uint32),
        ("skip", c_uint32),
        ("white_background", c_uint32),
        ("skip_missing", c_uint32),
        ("llff_holdout", c_uint32),
        ("forward_facing", c_uint32),
        ("hooks", POINTER(Hooks)),
        ("ignore_masks", c_uint32),
    ]


class TrainerOptions(_Versioned):
    """``nerf_trainer_options``: how a trainer draws and weighs rays.

    ``checkpoint_path`` accepts a str or path; it is stored encoded with
    :func:`os.fsencode` (a NUL character in it raises ValueError) and kept
    alive by the struct.
    ``random_background`` (0 or 1, default 0): 1 composites each training
    ray's target (an image with alpha) and its render onto the same random
    colour, so that the model cannot fill empty space with the background's
    colour; images without alpha ignore it.
    """

    _c_name_ = "nerf_trainer_options"
    _c_init_ = "nerf_trainer_options_init"
    _fields_ = [
        ("struct_size", c_uint32),
        ("batch_rays", c_uint32),
        ("precrop_steps", c_uint32),
        ("precrop_fraction", c_float),
        ("raw_noise_std", c_float),
        ("white_background", c_int32),
        ("checkpoint_every", c_uint32),
        ("reserved0", c_uint32),
        ("checkpoint_path", c_char_p),
        ("hooks", POINTER(Hooks)),
        ("batch_samples", c_uint32),
        ("random_background", c_int32),
        # Appended in libnerf 0.5: data-parallel training.  The hooks are
        # C function pointers for a transport written in C (nerf-train-mpi);
        # the binding leaves them NULL.
        ("worker_rank", c_uint32),
        ("worker_count", c_uint32),
        ("grad_hook", GRAD_HOOK),
        ("checksum_hook", CHECKSUM_HOOK),
        ("hook_user", c_void_p),
        ("checksum_every", c_uint32),
        ("reserved1", c_uint32),
        # Appended in libnerf 0.6.
        ("checkpoint_seconds", c_double),
        # Appended in libnerf 0.12.
        ("render_march_steps", c_uint32),
        # Formerly reserved2 (0 = no codes); libnerf 0.13.
        ("appearance_codes", c_uint32),
    ]
    _private_ = ("struct_size", "hooks", "grad_hook", "checksum_hook",
                 "hook_user", "reserved1")

    def _get(self, name: str) -> Any:
        value = getattr(self, name)
        if name == "checkpoint_path" and value is not None:
            return os.fsdecode(value)
        return value


class TrainStatsStruct(_Versioned):
    """``nerf_train_stats``: figures of one training step."""

    _c_name_ = "nerf_train_stats"
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved0", c_uint32),
        ("step", c_uint64),
        ("loss", c_double),
        ("psnr", c_double),
        ("psnr_coarse", c_double),
        ("learning_rate", c_double),
        # Appended in libnerf 0.2.
        ("samples_per_ray", c_double),
        ("rays", c_uint64),
    ]


# nerf_schedule_state: ScheduleStruct.state.
SCHEDULE_STEPS = 0
SCHEDULE_MEASURING = 1
SCHEDULE_FITTED = 2


class ScheduleStruct(_Versioned):
    """``nerf_schedule``: how a model's learning-rate schedule came about
    (since libnerf 0.5)."""

    _c_name_ = "nerf_schedule"
    _fields_ = [
        ("struct_size", c_uint32),
        ("state", c_uint32),
        ("budget_seconds", c_double),
        ("steps_per_second", c_double),
        ("fit_step", c_uint64),
        ("total_steps", c_uint64),
    ]


def read_covered(struct: ctypes.Structure, size: int) -> Dict[str, Any]:
    """Fields of a library-filled struct that ``size`` bytes cover; fields
    beyond it (an older library) are left out."""
    out = {}
    for name, *_ in struct._fields_:
        field = getattr(type(struct), name)
        if field.offset + field.size <= size:
            out[name] = getattr(struct, name)
    return out


# nerf_progress_kind
PROGRESS_RENDER = 1
PROGRESS_TRAIN = 2
PROGRESS_GEOMETRY = 3
PROGRESS_BAKE = 4
PROGRESS_KINDS = {PROGRESS_RENDER: "render", PROGRESS_TRAIN: "train",
                  PROGRESS_GEOMETRY: "geometry", PROGRESS_BAKE: "bake"}

# nerf_points_format (libnerf 0.5)
POINTS_PLY_BINARY = 0
POINTS_PLY_ASCII = 1
#: PointsOptions' defaults: the opacity a ray must reach, the most points.
POINTS_DEFAULT_OPACITY = 0.9
POINTS_DEFAULT_MAX = 1000000


@dataclass(frozen=True)
class Progress:
    """One progress report, as passed to a Python progress callback.

    ``kind`` is ``"render"`` (``done``/``total`` count rays) or ``"train"``
    (they count steps; ``loss`` and ``psnr`` are those of the last step).
    """

    kind: str
    done: int
    total: int
    elapsed: float
    loss: float = 0.0
    psnr: float = 0.0

    @property
    def fraction(self) -> float:
        """``done / total`` (1.0 when total is 0)."""
        return self.done / self.total if self.total else 1.0

    @classmethod
    def from_struct(cls, p: ProgressStruct) -> "Progress":
        """Read the fields the library's struct_size covers."""
        v = read_covered(p, p.struct_size)
        kind = v.get("kind", 0)
        return cls(kind=PROGRESS_KINDS.get(kind, str(kind)),
                   done=v.get("done", 0), total=v.get("total", 0),
                   elapsed=v.get("elapsed", 0.0), loss=v.get("loss", 0.0),
                   psnr=v.get("psnr", 0.0))


@dataclass(frozen=True)
class TrainStats:
    """Figures of one training step (``nerf_train_stats``)."""

    step: int
    loss: float
    psnr: float
    psnr_coarse: float
    learning_rate: float
    #: Network evaluations per ray (0 from a library before 0.2, which
    #: leaves the field as the binding zeroed it).
    samples_per_ray: float = 0.0
    #: Rays the step trained on (0 from a library before 0.2).
    rays: int = 0

    @classmethod
    def from_struct(cls, s: TrainStatsStruct) -> "TrainStats":
        """Read the fields the library wrote."""
        return cls(step=s.step, loss=s.loss, psnr=s.psnr,
                   psnr_coarse=s.psnr_coarse, learning_rate=s.learning_rate,
                   samples_per_ray=s.samples_per_ray, rays=s.rays)


def _vec3(v: Any, name: str) -> Any:
    # nerf_camera_look_at refuses points that are not finite.
    return _buffers.as_float_input(v, name, shape=(3,), finite=True)


#: Shapes a pose may have: 3 x 4, or 4 x 4 with the last row 0 0 0 1
#: (flat: 12 or 16 numbers, row by row).
POSE_SHAPES = [(3, 4), (4, 4)]
# As the library's loaders allow in the last row of a 4 x 4 pose
# (nerf__pose_problem): exported matrices carry float noise.
_LAST_ROW_SLACK = 1e-4


class Camera(_Versioned):
    """``nerf_camera``: a camera (OpenGL axes: x right, y up, the camera
    looks down -z), pinhole unless its lens distortion k1, k2, p1, p2, k3
    (OpenCV's model, see nerf.h) is set, plus helpers.

    The defaults from ``nerf_camera_init`` (identity pose, zero intrinsics)
    are not a usable camera: set width, height, fx, fy (and usually cx, cy),
    or build one with :meth:`from_fov`.  ``c2w`` is the 3 x 4 row-major
    camera-to-world matrix as 12 floats; :attr:`pose` reads and writes it
    as 3 rows of 4.
    """

    _c_name_ = "nerf_camera"
    _c_init_ = "nerf_camera_init"
    _private_ = ("struct_size",)
    _fields_ = [
        ("struct_size", c_uint32),
        ("flags", c_uint32),
        ("width", c_uint32),
        ("height", c_uint32),
        ("c2w", c_float * 12),
        ("fx", c_float),
        ("fy", c_float),
        ("cx", c_float),
        ("cy", c_float),
        ("k1", c_float),
        ("k2", c_float),
        ("p1", c_float),
        ("p2", c_float),
        ("k3", c_float),
    ]

    def _set(self, name: str, value: Any) -> None:
        if name == "c2w":
            self.pose = value
        else:
            setattr(self, name, value)

    def _get(self, name: str) -> Any:
        return list(self.c2w) if name == "c2w" else getattr(self, name)

    @property
    def pose(self) -> list:
        """The camera-to-world matrix as 3 rows of 4 floats."""
        v = list(self.c2w)
        return [v[0:4], v[4:8], v[8:12]]

    @pose.setter
    def pose(self, value: Any) -> None:
        # Every camera call refuses a pose that is not finite.
        buf = _buffers.as_float_input(value, "pose", shape=POSE_SHAPES,
                                      finite=True)
        if buf.shape == (4, 4):
            last = [buf.ptr[12 + i] for i in range(4)]
            if any(abs(v - w) > _LAST_ROW_SLACK
                   for v, w in zip(last, (0.0, 0.0, 0.0, 1.0))):
                raise ValueError("pose: a 4 x 4 pose must end with the row "
                                 "0 0 0 1, not %s"
                                 % " ".join("%g" % v for v in last))
        ctypes.memmove(self.c2w, buf.ptr, 12 * 4)

    def check(self, what: str = "camera") -> None:
        """Raise :class:`nerf.NerfInvalidArgument` (a ValueError), naming
        ``what`` and the camera's size, if the library would refuse this
        camera: the library's own check (``nerf_camera_rays`` over no
        pixels: sides 1..65536, positive finite focal lengths, a finite
        principal point, pose and lens).  Render calls make it before they
        allocate the arrays the camera's size asks for."""
        try:
            _capi().nerf_camera_rays(ctypes.byref(self), 0, 0, None, None)
        except errors.NerfError as err:
            reason = err.message
            prefix = "nerf_camera_rays: "
            if reason.startswith(prefix):
                reason = reason[len(prefix):]
            raise errors.error_for_status(
                err.code, "%s: %s (a %d x %d camera)"
                % (what, reason, self.width, self.height)) from None

    @property
    def pixel_count(self) -> int:
        """width x height."""
        return int(self.width) * int(self.height)

    @classmethod
    def from_fov(cls, width: int, height: int, fov_x: float,
                 eye: Sequence[float] = None,
                 target: Sequence[float] = (0.0, 0.0, 0.0),
                 up: Sequence[float] = (0.0, 0.0, 1.0),
                 pixel_corner: bool = False) -> "Camera":
        """A camera of ``width`` x ``height`` pixels with a horizontal field
        of view of ``fov_x`` degrees, square pixels and the principal point
        at the centre, looking from ``eye`` at ``target`` if ``eye`` is
        given (``up`` defaults to +z, as in Blender scenes)."""
        if not 0.0 < fov_x < 180.0:
            raise ValueError("fov_x must be in (0, 180) degrees, not %r"
                             % (fov_x,))
        focal = 0.5 * width / math.tan(0.5 * math.radians(fov_x))
        cam = cls(width=width, height=height, fx=focal, fy=focal,
                  cx=0.5 * width, cy=0.5 * height,
                  flags=1 if pixel_corner else 0)
        if eye is not None:
            cam.look_at(eye, target, up)
        return cam

    def look_at(self, eye: Sequence[float],
                target: Sequence[float] = (0.0, 0.0, 0.0),
                up: Sequence[float] = (0.0, 0.0, 1.0)) -> "Camera":
        """Point the camera from ``eye`` at ``target`` with ``up`` upwards
        in the image (``nerf_camera_look_at``).  Returns the camera."""
        e, t, u = _vec3(eye, "eye"), _vec3(target, "target"), _vec3(up, "up")
        _capi().nerf_camera_look_at(ctypes.byref(self), e.ptr, t.ptr, u.ptr)
        return self

    def rays(self, first: int = 0, count: int = None) -> Tuple[Any, Any]:
        """Origins and unnormalised directions of pixels ``first`` ..
        ``first + count - 1`` (row by row; all remaining pixels by default),
        as two ``count`` x 3 float arrays (``nerf_camera_rays``)."""
        self.check("rays: camera")
        first = integer(first, "rays: first", c_size_t)
        pixels = self.pixel_count
        if count is None:
            count = max(pixels - first, 0)
        count = integer(count, "rays: count", c_size_t)
        if first + count > pixels:
            # As nerf_camera_rays would refuse it, after the allocation.
            raise errors.NerfInvalidArgument(
                errors.EINVAL, "rays: pixels %d to %d are beyond the %d x %d "
                "image" % (first, first + count - 1, self.width, self.height))
        origins = _buffers.FloatOutput((count, 3), "origins")
        dirs = _buffers.FloatOutput((count, 3), "directions")
        _capi().nerf_camera_rays(ctypes.byref(self), first, count,
                                 origins.ptr, dirs.ptr)
        return origins.release(), dirs.release()


#: Every struct mirror, for the layout test.
ALL_STRUCTS = (Hooks, ModelOptions, SceneOptions, Camera, SamplerOptions,
               ProgressStruct, RendererOptions, DatasetOptions,
               TrainerOptions, TrainStatsStruct, CameraPathOptions,
               ScheduleStruct, PointsOptions, MeshOptions,
               ExchangeStruct, BakeOptions, BakeStats)

for _cls in ALL_STRUCTS:
    _check_fields(_cls)
# After the checks: a named field sets its int through the checked one.
_name_fields(ModelOptions, {
    "encoding": Encoding, "encoding_flags": EncodingFlags,
    "dir_encoding": DirEncoding, "density_activation": DensityActivation,
    "matmul": Matmul, "space": Space})
