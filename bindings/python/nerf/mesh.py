"""``nerf.Mesh``: a triangle mesh extracted from a model
(:meth:`nerf.Model.mesh`), and the density grid export."""

from __future__ import annotations

import ctypes
import json
import os
from typing import Any, Callable, Dict, Optional, Sequence

from . import _buffers, _handle
from ._capi import MeshP, lib
from .structs import PROGRESS_CB, MeshOptions, Progress, c_int, integer

# nerf_mesh_colour
MESH_COLOUR_NONE = 0
MESH_COLOUR_NORMAL = 1

# nerf_mesh_format
MESH_FORMAT_AUTO = 0
MESH_FORMAT_PLY = 1
MESH_FORMAT_PLY_ASCII = 2
MESH_FORMAT_OBJ = 3
MESH_FORMATS = {"auto": MESH_FORMAT_AUTO, "ply": MESH_FORMAT_PLY,
                "ply_ascii": MESH_FORMAT_PLY_ASCII, "obj": MESH_FORMAT_OBJ}

ProgressFn = Optional[Callable[[Progress], Any]]


def _copy(ptr: Any, count: int, ctype: Any, fmt: str, width: int) -> Any:
    """count x width items at ptr, copied: a NumPy array, or a memoryview of
    that shape without NumPy."""
    n = count * width
    if _buffers.np is not None:
        np = _buffers.np
        dtype = {"f": np.float32, "I": np.uint32, "B": np.uint8}[fmt]
        if n == 0 or not ptr:
            return np.zeros((count, width), dtype=dtype)
        return np.ctypeslib.as_array(ptr, shape=(count, width)).astype(
            dtype, copy=True)
    size = n * ctypes.sizeof(ctype)
    store = bytearray(ctypes.string_at(ptr, size) if n and ptr else b"")
    view = memoryview(store).cast(fmt)
    return view.cast("B").cast(fmt, (count, width)) if n else view


def mesh_options(**fields: Any) -> MeshOptions:
    """A :class:`MeshOptions` with ``fields`` set; ``colour`` may be a bool
    and ``box`` any 6 numbers (None: the model's bounds)."""
    if fields.get("box", ()) is None:
        del fields["box"]
    if isinstance(fields.get("colour"), bool):
        fields["colour"] = (MESH_COLOUR_NORMAL if fields["colour"]
                            else MESH_COLOUR_NONE)
    for flag in ("keep_largest",):
        if isinstance(fields.get(flag), bool):
            fields[flag] = int(fields[flag])
    return MeshOptions(**fields)


def run_with_progress(opts: MeshOptions, progress: ProgressFn,
                      fn: Callable[..., Any], *args: Any) -> Any:
    """Call ``fn(*args)`` with ``progress`` installed in ``opts``: a true
    return value cancels (NerfCancelled), an exception raised by the
    callback is re-raised, and Ctrl-C stops the call after a plane."""
    slot = _handle.ProgressSlot("Model")
    opts.progress = slot.thunk
    try:
        return slot.run(fn, *args, progress=progress)
    finally:
        opts.progress = PROGRESS_CB()


class Mesh(_handle.Handle):
    """A triangle mesh (``nerf_mesh``), from :meth:`nerf.Model.mesh`.

    ``vertices`` (n x 3 float32), ``faces`` (m x 3 uint32, counter-clockwise
    seen from outside), ``normals`` (n x 3 float32) and ``colours`` (n x 3
    uint8, None without colours) are copies, NumPy arrays when NumPy is
    installed (memoryviews of that shape otherwise).
    """

    _kind = "Mesh"

    def __init__(self, res: _handle._Resource) -> None:
        super().__init__(res)
        with self._using() as ptr:
            nv = int(lib.nerf_mesh_vertex_count(ptr))
            nf = int(lib.nerf_mesh_face_count(ptr))
            self.vertices = _copy(lib.nerf_mesh_vertices(ptr), nv,
                                  ctypes.c_float, "f", 3)
            self.faces = _copy(lib.nerf_mesh_faces(ptr), nf,
                               ctypes.c_uint32, "I", 3)
            self.normals = _copy(lib.nerf_mesh_normals(ptr), nv,
                                 ctypes.c_float, "f", 3)
            colours = lib.nerf_mesh_colours(ptr)
            self.colours = (_copy(colours, nv, ctypes.c_uint8, "B", 3)
                            if colours else None)

    @property
    def vertex_count(self) -> int:
        return len(self.vertices)

    @property
    def face_count(self) -> int:
        return len(self.faces)

    def write(self, path: Any, format: Any = "auto") -> None:
        """Write the mesh (``nerf_mesh_write``): ``format`` "auto" (by the
        extension: .ply binary, .obj), "ply", "ply_ascii" or "obj"."""
        if isinstance(format, str):
            if format not in MESH_FORMATS:
                raise ValueError("unknown mesh format %r (one of %s)"
                                 % (format, ", ".join(MESH_FORMATS)))
            format = MESH_FORMATS[format]
        with self._using() as ptr:
            lib.nerf_mesh_write(ptr, _handle.fspath(path),
                                integer(format, "format", c_int))


def extract(model_res: Any, model_ptr: Any, opts: MeshOptions,
            progress: ProgressFn) -> Mesh:
    """``nerf_mesh_extract`` on a model the caller holds."""
    out = MeshP()

    def call() -> None:
        lib.nerf_mesh_extract(ctypes.byref(out), model_ptr,
                              ctypes.byref(opts))

    run_with_progress(opts, progress, call)
    res = _handle._Resource("Mesh", out,
                            _handle.destroyer("nerf_mesh_destroy"), (), None)
    return Mesh(res)


def write_grid(model_ptr: Any, path: Any, opts: MeshOptions,
               progress: ProgressFn) -> Dict[str, Any]:
    """``nerf_density_grid_write``; returns the JSON sidecar as a dict."""
    path_b = _handle.fspath(path)
    run_with_progress(opts, progress, lambda: lib.nerf_density_grid_write(
        model_ptr, path_b, ctypes.byref(opts)))
    text = os.fsdecode(path_b)
    base = text[:-4] if text.endswith(".npy") else text
    with open(base + ".json", encoding="utf-8") as f:
        return json.load(f)


__all__: Sequence[str] = ("Mesh", "MESH_COLOUR_NONE", "MESH_COLOUR_NORMAL",
                          "MESH_FORMATS")
