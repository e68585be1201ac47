"""``nerf.Sampler`` and ``nerf.Renderer``."""

from __future__ import annotations

import contextlib
import ctypes
from typing import Any, Callable, NamedTuple, Optional, Union

from . import _buffers, _handle
from ._capi import PointsP, RendererP, SamplerP, lib
from .model import Model, preset_key
from .structs import (POINTS_PLY_ASCII, POINTS_PLY_BINARY, Camera,
                      PointsOptions, Progress, RendererOptions,
                      SamplerOptions, c_size_t, c_uint32, c_uint64,
                      integer)

#: Flag of the sampling calls: random placement as in training.
SAMPLE_TRAINING = 0x1

# nerf_sampler_use: what nerf_sampler_options_for() sets a sampler up for.
SAMPLER_FOR_RENDERING = 0
SAMPLER_FOR_TRAINING = 1
#: Sentinel of ``raw_noise_std``: chosen from the sampler (1 with NDC).
NOISE_AUTO = -1.0
#: Flag of ``Camera.flags``: rays through pixel corners, as the reference.
CAMERA_PIXEL_CORNER = 0x1

LogFn = Optional[Callable[[int, str], Any]]
ProgressFn = Optional[Callable[[Progress], Any]]


class Sampler(_handle.Handle):
    """Places samples along rays (``nerf_sampler``); immutable once made.

    ``Sampler(preset="tiny", seed=0, t_near=2, t_far=6, ...)``: the
    library's defaults (the reference setup for Blender scenes), then
    ``preset``'s sampling settings, then the keyword fields of
    :class:`nerf.SamplerOptions`.  See :meth:`for_dataset` for a sampler
    matching a dataset's bounds and NDC setting.
    """

    _kind = "Sampler"

    def __init__(self, preset: Union[str, int, None] = None, seed: int = 0,
                 *, log: LogFn = None, log_level: Optional[int] = None,
                 **options: Any) -> None:
        opts = SamplerOptions()
        if preset is not None:
            lib.nerf_sampler_options_preset(ctypes.byref(opts),
                                            preset_key(preset))
        opts.seed = seed
        opts.update(**options)
        hooks = _handle.make_hooks(log, log_level)
        if hooks is not None:
            opts.hooks = ctypes.pointer(hooks[0])
        res = _handle.create("Sampler", SamplerP, lib.nerf_sampler_create,
                             _handle.destroyer("nerf_sampler_destroy"),
                             ctypes.byref(opts),
                             keep=hooks[1] if hooks else None)
        super().__init__(res)
        # The library has no getter for a sampler's options; keep a copy.
        opts.hooks = None
        self._options = opts

    @classmethod
    def for_dataset(cls, dataset: Any, preset: Union[str, int, None] = None,
                    seed: int = 0, **options: Any) -> "Sampler":
        """A sampler for rendering or training on ``dataset``: ``preset``'s
        counts, the dataset's bounds, its NDC setting and, for NDC scenes,
        the frustum of its first camera, so renders at other sizes see the
        same warped scene (``nerf_sampler_options_for`` without a model).
        ``options`` override any of these."""
        return cls._for(None, dataset, SAMPLER_FOR_RENDERING, preset, seed,
                        options)

    @classmethod
    def for_model(cls, model: Model, dataset: Any = None, *,
                  training: bool = False, seed: int = 0,
                  march_steps: Optional[int] = None,
                  **options: Any) -> "Sampler":
        """The sampler ``nerf-train`` (``training=True``) or ``nerf-render``
        uses for ``model`` on ``dataset`` (``nerf_sampler_options_for``):
        the model's recorded sampling, or its preset's, with a marching
        model trained in the preset's march and rendered in the finer one
        it records; the dataset's bounds and NDC frustum (None: the
        model's).  ``march_steps``: another march for a marching model,
        its cap on a ray's samples scaled to reach as far
        (``nerf_sampler_options_set_march``, as ``nerf-render
        --march-steps``).  ``options`` override any field."""
        if not isinstance(model, Model):
            raise TypeError("model must be a nerf.Model")
        use = SAMPLER_FOR_TRAINING if training else SAMPLER_FOR_RENDERING
        return cls._for(model, dataset, use, None, seed, options,
                        march_steps)

    @classmethod
    def _for(cls, model: Optional[Model], dataset: Any, use: int,
             preset: Union[str, int, None], seed: int, options: dict,
             march_steps: Optional[int] = None) -> "Sampler":
        opts = SamplerOptions()
        if preset is not None:
            lib.nerf_sampler_options_preset(ctypes.byref(opts),
                                            preset_key(preset))
        with contextlib.ExitStack() as stack:
            mp = stack.enter_context(model._using()) if model else None
            dp = stack.enter_context(dataset._using()) if dataset else None
            lib.nerf_sampler_options_for(ctypes.byref(opts), mp, dp, use)
        if march_steps is not None:
            lib.nerf_sampler_options_set_march(
                ctypes.byref(opts),
                integer(march_steps, "march_steps", c_uint32))
        fields = opts.to_dict()
        del fields["seed"]  # the argument's
        fields.update(options)
        return cls(None, seed, **fields)

    @property
    def options(self) -> SamplerOptions:
        """A copy of the options the sampler was created with."""
        return self._options.copy()

    @property
    def n_coarse(self) -> int:
        """Stratified samples per ray."""
        return int(self._options.n_coarse)

    @property
    def n_fine(self) -> int:
        """Hierarchical samples per ray (0: coarse pass only)."""
        return int(self._options.n_fine)

    def sample_coarse(self, n_rays: int, training: bool = False,
                      first_ray: int = 0, u: Any = None) -> Any:
        """Stratified depths, ``n_rays`` x ``n_coarse`` increasing values
        of t (``nerf_sampler_sample_coarse``).  ``u``: optional
        ``n_rays`` x ``n_coarse`` uniforms replacing the generator's when
        ``training``."""
        n_rays = integer(n_rays, "sample_coarse: n_rays", c_size_t)
        first_ray = integer(first_ray, "sample_coarse: first_ray", c_uint64)
        uu = self._uniforms(u, (n_rays, self.n_coarse), "u")
        out = _buffers.FloatOutput((n_rays, self.n_coarse), "t")
        with self._using() as ptr:
            lib.nerf_sampler_sample_coarse(
                ptr, n_rays, SAMPLE_TRAINING if training else 0,
                first_ray, uu.ptr if uu else None, out.ptr)
        return out.release()

    def sample_fine(self, t_coarse: Any, weights: Any, training: bool = False,
                    first_ray: int = 0, u: Any = None) -> Any:
        """Hierarchical depths merged with the coarse ones:
        ``n_rays`` x (``n_coarse`` + ``n_fine``) sorted values
        (``nerf_sampler_sample_fine``).

        Args:
            t_coarse: ``n_rays`` x ``n_coarse`` increasing depths.
            weights: the compositing weights of those samples, same shape.
            u: optional ``n_rays`` x ``n_fine`` uniforms for training.
        """
        t = _buffers.as_float_input(t_coarse, "t_coarse",
                                    shape=(None, self.n_coarse))
        n_rays = t.shape[0]
        w = _buffers.as_float_input(weights, "weights", shape=t.shape)
        first_ray = integer(first_ray, "sample_fine: first_ray", c_uint64)
        uu = self._uniforms(u, (n_rays, self.n_fine), "u")
        out = _buffers.FloatOutput((n_rays, self.n_coarse + self.n_fine), "t")
        with self._using() as ptr:
            lib.nerf_sampler_sample_fine(
                ptr, n_rays, SAMPLE_TRAINING if training else 0,
                first_ray, t.ptr, w.ptr, uu.ptr if uu else None, out.ptr)
        return out.release()

    @staticmethod
    def _uniforms(u: Any, shape: Any, name: str):
        if u is None:
            return None
        return _buffers.as_float_input(u, name, shape=shape)


class RenderResult(NamedTuple):
    """What a render returns; outputs not asked for are None."""

    rgb: Any
    depth: Any
    opacity: Any


class DepthResult(NamedTuple):
    """What :meth:`Renderer.render_depth` returns; outputs not asked for
    are None.  ``distance`` and ``zdepth`` are in world units (see
    ``nerf_renderer_render_depth``)."""

    rgb: Any
    distance: Any
    zdepth: Any
    opacity: Any


class PointCloud(_handle.Handle):
    """A point cloud (``nerf_points``), made by :meth:`Renderer.points`.

    ``positions`` (n x 3 float32, world units), ``colours`` (n x 3 uint8)
    and ``normals`` (n x 3 float32, unit length or 0 0 0 where none could
    be estimated) are copies of the C arrays, made once, so they stay valid
    after :meth:`close`.  :meth:`write` saves the cloud as PLY.
    """

    _kind = "PointCloud"

    def __init__(self, res: Any) -> None:
        super().__init__(res)
        with self._using() as ptr:
            n = int(lib.nerf_points_count(ptr))
            pos = ctypes.POINTER(ctypes.c_float)()
            nrm = ctypes.POINTER(ctypes.c_float)()
            col = ctypes.POINTER(ctypes.c_uint8)()
            lib.nerf_points_arrays(ptr, ctypes.byref(pos), ctypes.byref(col),
                                   ctypes.byref(nrm))
            self.positions = _copy_out(pos, n, ctypes.c_float)
            self.normals = _copy_out(nrm, n, ctypes.c_float)
            self.colours = _copy_out(col, n, ctypes.c_uint8)
        self.count = n

    def __len__(self) -> int:
        return self.count

    def write(self, path: Any, ascii: bool = False) -> None:
        """Write the cloud to ``path`` as PLY, binary little-endian (or
        ASCII), through a temporary file renamed into place."""
        with self._using() as ptr:
            lib.nerf_points_write(ptr, _handle.fspath(path),
                                  POINTS_PLY_ASCII if ascii
                                  else POINTS_PLY_BINARY)


def _copy_out(ptr: Any, n: int, ctype: Any) -> Any:
    """n x 3 values of ctype at ptr, copied into a new array."""
    is_float = ctype is ctypes.c_float
    out = (_buffers.FloatOutput((n, 3)) if is_float
           else _buffers.Uint8Output((n, 3)))
    if n:
        ctypes.memmove(out.ptr, ptr, 3 * n * ctypes.sizeof(ctype))
    return out.release()


def _camera_arg(camera: Any, what: str) -> Camera:
    """The camera of a render call, checked as the library will check it,
    before the call allocates the outputs it sizes."""
    if not isinstance(camera, Camera):
        raise TypeError("%s must be a nerf.Camera, not %s"
                        % (what, type(camera).__name__))
    camera.check(what)
    return camera


def _image_outputs(fn: str, cam: Camera, wanted: Any) -> list:
    """The output arrays of a render of cam: one per (name, channels, ask),
    None where not asked; MemoryError says the size when they do not fit."""
    h, w = int(cam.height), int(cam.width)
    out = []
    for name, channels, ask in wanted:
        shape = (h, w, channels) if channels > 1 else (h, w)
        if not ask:
            out.append(None)
        elif name == "rgb8":
            out.append(_buffers.Uint8Output(shape, "%s: rgb" % fn))
        else:
            out.append(_buffers.FloatOutput(shape, "%s: %s" % (fn, name)))
    return out


def render_image_call(fn: str, camera: Any, wanted: Any,
                      call: Callable[[Camera, list], Any]) -> RenderResult:
    """An image render: the camera checked, the outputs of wanted (as
    _image_outputs) allocated, call(camera, their pointers) made."""
    cam = _camera_arg(camera, fn + ": camera")
    outs = _image_outputs(fn, cam, wanted)
    call(cam, [o.ptr if o else None for o in outs])
    return RenderResult(*(o.release() if o else None for o in outs))


class Renderer(_handle.ProgressHandle):
    """Draws a model with a sampler's samples (``nerf_renderer``).

    ``Renderer(model, sampler, white_background=1, threads=0, ...)``; the
    keyword fields are those of :class:`nerf.RendererOptions`.  Without a
    sampler, ``Renderer(model)`` renders as the model was trained: its
    recorded sample counts, bounds, NDC frustum and background
    (:meth:`nerf.Model.render_settings`; guessed from the model's shape
    for files from before libnerf 0.4); keyword fields still override.  The renderer
    keeps its model and sampler alive, and reads the model's current
    weights at every call, so training in between is seen.

    ``progress``: a callable ``progress(nerf.Progress)`` called after every
    chunk of rays; return a true value to cancel (the render then raises
    :class:`nerf.NerfCancelled`).  If it raises, the render stops and that
    exception propagates instead.
    """

    _kind = "Renderer"

    def __init__(self, model: Model, sampler: Optional[Sampler] = None, *,
                 progress: ProgressFn = None, log: LogFn = None,
                 log_level: Optional[int] = None, **options: Any) -> None:
        if not isinstance(model, Model):
            raise TypeError("model must be a nerf.Model")
        if sampler is None:
            # What the model was trained with (Model.render_settings).
            so, ro = model.render_settings()
            sampler = Sampler(**so.to_dict())
            options.setdefault("white_background", ro.white_background)
        if not isinstance(sampler, Sampler):
            raise TypeError("sampler must be a nerf.Sampler")
        opts = RendererOptions(**options)
        hooks = _handle.make_hooks(log, log_level)
        if hooks is not None:
            opts.hooks = ctypes.pointer(hooks[0])
        self._slot = _handle.ProgressSlot("Renderer")
        self._slot.callback = progress
        keep = [self._slot.thunk] + (list(hooks[1]) if hooks else [])
        with model._using() as mp, sampler._using() as sp:
            res = _handle.create("Renderer", RendererP,
                                 lib.nerf_renderer_create,
                                 _handle.destroyer("nerf_renderer_destroy"),
                                 mp, sp, ctypes.byref(opts),
                                 deps=(model._res, sampler._res), keep=keep)
        super().__init__(res)
        self.model = model
        self.sampler = sampler
        with self._using() as ptr:
            lib.nerf_renderer_set_progress(ptr, self._slot.thunk, None)

    def cancel(self) -> None:
        """Ask a render running on another thread (or in the progress
        callback) to stop; it raises NerfCancelled.  Thread-safe; a no-op
        when nothing runs or the renderer is closed."""
        try:
            ptr = self._res.acquire()
        except ValueError:
            return
        try:
            lib.nerf_renderer_cancel(ptr)
        finally:
            self._res.release()

    def render_image(self, camera: Camera, *, rgb: bool = True,
                     depth: bool = True, opacity: bool = True,
                     progress: ProgressFn = None) -> RenderResult:
        """Render every pixel of ``camera`` (``nerf_renderer_render_image``).

        Returns:
            RenderResult: ``rgb`` height x width x 3, ``depth`` and
            ``opacity`` height x width floats; those not asked for are None.
        """
        if not (rgb or depth or opacity):
            raise ValueError("render_image: ask for at least one output")

        def call(cam: Camera, ptrs: list) -> None:
            with self._using() as ptr:
                self._slot.run(lib.nerf_renderer_render_image, ptr,
                               ctypes.byref(cam), *ptrs, cam.pixel_count,
                               progress=progress)
        return render_image_call("render_image", camera, (
            ("rgb", 3, rgb), ("depth", 1, depth), ("opacity", 1, opacity)),
            call)

    def render_image_u8(self, camera: Camera, *, depth: bool = False,
                        opacity: bool = False,
                        progress: ProgressFn = None) -> RenderResult:
        """As :meth:`render_image` with 8-bit colours, round(255 clamp(c)):
        ``rgb`` is height x width x 3 uint8 (``bytes``-like without NumPy).
        """
        def call(cam: Camera, ptrs: list) -> None:
            with self._using() as ptr:
                self._slot.run(lib.nerf_renderer_render_image_u8, ptr,
                               ctypes.byref(cam), *ptrs, cam.pixel_count,
                               progress=progress)
        return render_image_call("render_image_u8", camera, (
            ("rgb8", 3, True), ("depth", 1, depth), ("opacity", 1, opacity)),
            call)

    def render_rays(self, origins: Any, directions: Any, *, rgb: bool = True,
                    depth: bool = True, opacity: bool = True,
                    progress: ProgressFn = None) -> RenderResult:
        """Render a batch of rays (``nerf_renderer_render_rays``).

        Args:
            origins: n x 3 floats, world units.
            directions: n x 3 unnormalised directions (distances scale
                with their length), as :meth:`nerf.Camera.rays` gives.

        Returns:
            RenderResult: ``rgb`` n x 3, ``depth`` and ``opacity`` n floats.
        """
        if not (rgb or depth or opacity):
            raise ValueError("render_rays: ask for at least one output")
        # The library refuses rays that are not finite.
        o = _buffers.as_float_input(origins, "origins", shape=(None, 3),
                                    finite=True)
        n = o.shape[0]
        d = _buffers.as_float_input(directions, "directions", shape=(n, 3),
                                    finite=True)
        outs = [_buffers.FloatOutput((n, 3), "rgb") if rgb else None,
                _buffers.FloatOutput((n,), "depth") if depth else None,
                _buffers.FloatOutput((n,), "opacity") if opacity else None]
        ptrs = [x.ptr if x else None for x in outs]
        with self._using() as ptr:
            self._slot.run(lib.nerf_renderer_render_rays, ptr, n, o.ptr,
                           d.ptr, *ptrs, progress=progress)
        return RenderResult(*(x.release() if x else None for x in outs))

    def render_depth(self, camera: Camera, *, rgb: bool = True,
                     distance: bool = True, zdepth: bool = True,
                     opacity: bool = True,
                     progress: ProgressFn = None) -> DepthResult:
        """Render every pixel of ``camera`` with depths in world units
        (``nerf_renderer_render_depth``, libnerf 0.5).

        ``distance``: from the camera centre to the ray's expected
        termination point (sum(w t) / sum(w) along the ray, times |d|);
        ``zdepth``: the same point's depth along the optical axis.  Both
        are 0 where the opacity is 0; an NDC model's depths are converted
        to world units.  The arrays are those the library wrote into: no
        copy is made.

        Returns:
            DepthResult: ``rgb`` height x width x 3, the others height x
            width float32; those not asked for are None.
        """
        if not (rgb or distance or zdepth or opacity):
            raise ValueError("render_depth: ask for at least one output")
        cam = _camera_arg(camera, "render_depth: camera")
        outs = _image_outputs("render_depth", cam, (
            ("rgb", 3, rgb), ("distance", 1, distance),
            ("zdepth", 1, zdepth), ("opacity", 1, opacity)))
        ptrs = [o.ptr if o else None for o in outs]
        with self._using() as ptr:
            self._slot.run(lib.nerf_renderer_render_depth, ptr,
                           ctypes.byref(cam), *ptrs, cam.pixel_count,
                           progress=progress)
        return DepthResult(*(o.release() if o else None for o in outs))

    def points(self, cameras: Any, *, opacity_threshold: Optional[float] = None,
               max_points: Optional[int] = None, stride: int = 1,
               progress: ProgressFn = None) -> PointCloud:
        """A point cloud from the expected depth of the views of
        ``cameras`` (one :class:`nerf.Camera` or a sequence of them):
        one point per ray whose opacity reaches ``opacity_threshold``
        (default 0.9), at most ``max_points`` (default 10^6, thinned
        evenly), one ray per ``stride`` x ``stride`` pixels
        (``nerf_points_from_views``, libnerf 0.5).  ``progress`` reports
        rays over all views; a true return value cancels."""
        cams = [cameras] if isinstance(cameras, Camera) else list(cameras)
        if not cams:
            raise ValueError("points: no cameras")
        for i, cam in enumerate(cams):
            _camera_arg(cam, "points: cameras[%d]" % i)
        arr = (Camera * len(cams))(*cams)
        opts = PointsOptions(stride=stride)
        if opacity_threshold is not None:
            opts.opacity_threshold = float(opacity_threshold)
        if max_points is not None:
            opts.max_points = max_points
        opts.progress = self._slot.thunk
        out = PointsP()
        with self._using() as ptr:
            self._slot.run(lib.nerf_points_from_views, ctypes.byref(out),
                           ptr, arr, len(cams), ctypes.byref(opts),
                           progress=progress)
        res = _handle._Resource("PointCloud", out,
                                _handle.destroyer("nerf_points_destroy"))
        return PointCloud(res)
