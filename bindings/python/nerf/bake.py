"""Baked models (``nerf_bake``, since libnerf 0.14): a model's density and
colour looked up on the occupied cells of its grid instead of evaluated by
its networks, for fast renders."""

from __future__ import annotations

import ctypes
from typing import Any, Dict, Sequence

from . import _handle
from ._capi import BakeP, lib
from .mesh import run_with_progress
from .model import Model
from .render import RenderResult, render_image_call
from .structs import BakeOptions, BakeStats, Camera


class Bake(_handle.Handle):
    """``nerf_bake_create``: bake ``model`` (a marching model in a box or in
    NDC: the fast preset on a Blender-like, forward-facing or the built-in
    scene).

    ``subdivisions`` voxels along each occupancy cell's edge, colours as
    spherical harmonics of ``sh_degree`` fitted in ``directions``
    directions, at most ``max_bytes`` of memory (a larger bake raises
    NerfNoMemory); ``progress(p)`` is called as it goes, a true return
    cancels (NerfCancelled).  The bake copies what it needs: the model may
    change or go afterwards.
    """

    _kind = "Bake"

    def __init__(self, model: Model, *, progress: Any = None,
                 **options: Any) -> None:
        opts = BakeOptions(**options)
        out = BakeP()
        with model._using() as mptr:
            run_with_progress(opts, progress, lambda: lib.nerf_bake_create(
                ctypes.byref(out), mptr, ctypes.byref(opts)))
        super().__init__(_handle._Resource(
            "Bake", out, _handle.destroyer("nerf_bake_destroy"), (), None))

    @property
    def stats(self) -> Dict[str, int]:
        """``nerf_bake_stats_get``: resolution (voxels across the bound),
        bricks, points (colours fitted) and bytes held."""
        st = BakeStats()
        with self._using() as ptr:
            lib.nerf_bake_stats_get(ptr, ctypes.byref(st))
        return {name: int(getattr(st, name))
                for name in ("resolution", "bricks", "points", "bytes")}

    def render_image(self, camera: Camera, *, rgb: bool = True,
                     depth: bool = True,
                     opacity: bool = True) -> RenderResult:
        """Render every pixel of ``camera`` from the bake
        (``nerf_bake_render_image``), with the outputs of
        :meth:`nerf.Renderer.render_image`."""
        if not (rgb or depth or opacity):
            raise ValueError("render_image: ask for at least one output")

        def call(cam: Camera, ptrs: list) -> None:
            with self._using() as ptr:
                lib.nerf_bake_render_image(ptr, ctypes.byref(cam), *ptrs,
                                           cam.pixel_count)
        return render_image_call("render_image", camera, (
            ("rgb", 3, rgb), ("depth", 1, depth), ("opacity", 1, opacity)),
            call)


__all__: Sequence[str] = ("Bake",)
