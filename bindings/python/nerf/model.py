"""``nerf.Model``: the scene networks and their weights."""

from __future__ import annotations

import ctypes
import os
import warnings
from typing import Any, Callable, FrozenSet, Optional, Tuple, Union

from . import _buffers, _handle
from ._capi import ModelP, lib
from .core import param_key
from .structs import (ModelOptions, RendererOptions, SamplerOptions,
                      ScheduleStruct, c_int, integer)

# nerf_preset
PRESET_REFERENCE = 1
PRESET_TINY = 2
PRESET_FAST = 3
PRESETS = {"reference": PRESET_REFERENCE, "tiny": PRESET_TINY,
           "fast": PRESET_FAST}

# nerf_network
NETWORK_COARSE = 0
NETWORK_FINE = 1
NETWORKS = {"coarse": NETWORK_COARSE, "fine": NETWORK_FINE}

# nerf_encoding_kind and flags
ENCODING_FREQUENCY = 1
ENCODING_HASHGRID = 2
ENCODING_SPHERICAL_HARMONICS = 3
DENSITY_RELU = 0
DENSITY_EXP = 1
ENCODING_INCLUDE_INPUT = 0x1
ENCODING_SCALE_PI = 0x2

# nerf_matmul: how a model computes its matrix products.
MATMUL_FP32 = 0
MATMUL_BF16 = 1
MATMUL_FP32_ONEDNN = 2
MATMUL_FP32_FASTEST = 3
MATMULS = {"fp32": MATMUL_FP32, "bf16": MATMUL_BF16,
           "fp32-onednn": MATMUL_FP32_ONEDNN,
           "fp32-fastest": MATMUL_FP32_FASTEST}

# nerf_space: where a hash-grid model's grids lie.
SPACE_BOX = 0
SPACE_NDC = 1
SPACE_UNBOUNDED = 2
SPACES = {"box": SPACE_BOX, "ndc": SPACE_NDC, "unbounded": SPACE_UNBOUNDED}

# nerf_model_contents() bits, by the names Model.contents uses.
MODEL_HAS_OPTIMIZER = 0x1
MODEL_HAS_OCCUPANCY = 0x2
MODEL_HAS_RENDER_SETTINGS = 0x4
MODEL_HAS_DATA_RECORD = 0x8
MODEL_HAS_BATCH_RECORD = 0x10
MODEL_HAS_ADAM_CORRECTIONS = 0x20
MODEL_HAS_NONFINITE_WEIGHTS = 0x40
MODEL_HAS_APPEARANCE = 0x80
CONTENTS = {MODEL_HAS_OPTIMIZER: "optimizer",
            MODEL_HAS_OCCUPANCY: "occupancy",
            MODEL_HAS_RENDER_SETTINGS: "render_settings",
            MODEL_HAS_DATA_RECORD: "data_record",
            MODEL_HAS_BATCH_RECORD: "batch_record",
            MODEL_HAS_ADAM_CORRECTIONS: "adam_corrections",
            MODEL_HAS_NONFINITE_WEIGHTS: "nonfinite_weights",
            MODEL_HAS_APPEARANCE: "appearance"}

# nerf_renderer_options.appearance: the neutral look, or a training
# image's (appearance_of(i)).
APPEARANCE_NEUTRAL = 0
APPEARANCE_CODE_FLOATS = 3


def appearance_of(image: int) -> int:
    """``NERF_APPEARANCE_OF(image)``: training image ``image``'s
    appearance, for :class:`RendererOptions`' ``appearance``."""
    return integer(image, "image", ctypes.c_uint32) + 1

LogFn = Optional[Callable[[int, str], Any]]


def preset_key(preset: Union[str, int]) -> int:
    """A preset number from its name (``"reference"``, ``"tiny"``,
    ``"fast"``)."""
    if isinstance(preset, str):
        try:
            return PRESETS[preset]
        except KeyError:
            raise ValueError("unknown preset %r (known: %s)"
                             % (preset, ", ".join(PRESETS))) from None
    return integer(preset, "preset", c_int)


def network_key(network: Union[str, int]) -> int:
    """A network number from its name (``"coarse"``, ``"fine"``)."""
    if isinstance(network, str):
        try:
            return NETWORKS[network]
        except KeyError:
            raise ValueError("unknown network %r (known: coarse, fine)"
                             % (network,)) from None
    return integer(network, "network", c_int)


def matmul_key(matmul: Union[str, int]) -> int:
    """A nerf_matmul number from its name (``"fp32"``, ``"bf16"``,
    ``"fp32-onednn"``)."""
    if isinstance(matmul, str):
        try:
            return MATMULS[matmul]
        except KeyError:
            raise ValueError("unknown matmul %r (known: %s)"
                             % (matmul, ", ".join(MATMULS))) from None
    return integer(matmul, "matmul", c_int)


def space_key(space: Union[str, int]) -> int:
    """A nerf_space number from its name (``"box"``, ``"ndc"``,
    ``"unbounded"``)."""
    if isinstance(space, str):
        try:
            return SPACES[space]
        except KeyError:
            raise ValueError("unknown space %r (known: %s)"
                             % (space, ", ".join(SPACES))) from None
    return integer(space, "space", c_int)


def matmul_supported(matmul: Union[str, int]) -> bool:
    """Whether models with these products can be created here
    (``nerf_matmul_supported``): bf16 needs a libnerf built with oneDNN
    and a CPU with AVX512-BF16, fp32-onednn one built with oneDNN and a
    CPU with AVX-512."""
    return bool(lib.nerf_matmul_supported(matmul_key(matmul)))


def model_options(preset: Union[str, int, None] = None, seed: int = 0,
                  dataset: Any = None, **fields: Any) -> ModelOptions:
    """Options from the library's defaults, a preset (its network and
    learning rate), a hash-grid model placed in ``dataset``'s scene
    (``nerf_model_options_for_dataset``) when one is given, then ``fields``
    (``matmul`` and ``space`` may be given by name: ``matmul="bf16"``,
    ``space="ndc"``)."""
    opts = ModelOptions()
    if preset is not None:
        lib.nerf_model_options_preset(ctypes.byref(opts), preset_key(preset))
    if dataset is not None:
        with dataset._using() as dp:
            lib.nerf_model_options_for_dataset(ctypes.byref(opts), dp)
    opts.seed = seed
    if "matmul" in fields:
        fields["matmul"] = matmul_key(fields["matmul"])
    if "space" in fields:
        fields["space"] = space_key(fields["space"])
    opts.update(**fields)
    return opts


class Model(_handle.Handle):
    """A NeRF model (``nerf_model``).

    Create one with ``Model(preset="tiny", seed=0, width=64, ...)`` (the
    same as :meth:`create`), :meth:`load` or :meth:`import_npz`.  Keyword
    options are fields of :class:`nerf.ModelOptions`.  ``log`` (a callable
    ``log(level, message)``) receives this model's log lines; ``log_level``
    filters them.
    """

    _kind = "Model"

    def __init__(self, preset: Union[str, int, None] = None, seed: int = 0,
                 *, log: LogFn = None, log_level: Optional[int] = None,
                 dataset: Any = None, **options: Any) -> None:
        opts = model_options(preset, seed, dataset, **options)
        hooks = _handle.make_hooks(log, log_level)
        if hooks is not None:
            opts.hooks = ctypes.pointer(hooks[0])
        res = _handle.create("Model", ModelP, lib.nerf_model_create,
                             _handle.destroyer("nerf_model_destroy"),
                             ctypes.byref(opts),
                             keep=hooks[1] if hooks else None)
        super().__init__(res)

    @classmethod
    def create(cls, preset: Union[str, int, None] = None, seed: int = 0,
               *, log: LogFn = None, log_level: Optional[int] = None,
               **options: Any) -> "Model":
        """A model with fresh weights: the library's defaults (the paper's
        networks), then ``preset`` ("reference", "tiny" or "fast"), then
        ``options`` (fields of :class:`nerf.ModelOptions`)."""
        return cls(preset, seed, log=log, log_level=log_level, **options)

    @classmethod
    def for_dataset(cls, dataset: Any, preset: Union[str, int, None] = None,
                    seed: int = 0, *, log: LogFn = None,
                    log_level: Optional[int] = None,
                    **options: Any) -> "Model":
        """As :meth:`create`, with a hash-grid model's grids placed as
        ``dataset`` wants them (``nerf_model_options_for_dataset``: NDC for
        forward-facing scenes, a contracted space for unbounded ones);
        ``options`` override ``space`` and ``bound`` too.  With
        ``matmul="fp32-fastest"`` and a :meth:`nerf.Trainer.for_model`
        trainer, this is the model ``nerf-train`` makes."""
        return cls(preset, seed, log=log, log_level=log_level,
                   dataset=dataset, **options)

    @classmethod
    def _wrap(cls, res: _handle._Resource) -> "Model":
        model = cls.__new__(cls)
        _handle.Handle.__init__(model, res)
        return model

    @classmethod
    def load(cls, path: Any, *, log: LogFn = None,
             log_level: Optional[int] = None) -> "Model":
        """Load a checkpoint written by :meth:`save` (``nerf_model_load``).

        Raises NerfIOError, NerfFormatError or NerfVersionError, with a
        message naming the file.  A checkpoint of a run that diverged
        (weights NaN or infinite) loads, for inspection with :meth:`query`,
        with a RuntimeWarning (and the library's warning, saying where the
        first such weight is, in the log); its :attr:`contents` hold
        ``"nonfinite_weights"``, and renderers, trainers, meshes and
        :meth:`save` refuse it with NerfInvalidArgument.
        """
        hooks = _handle.make_hooks(log, log_level)
        res = _handle.create("Model", ModelP, lib.nerf_model_load,
                             _handle.destroyer("nerf_model_destroy"),
                             _handle.fspath(path),
                             ctypes.byref(hooks[0]) if hooks else None,
                             keep=hooks[1] if hooks else None)
        model = cls._wrap(res)
        if "nonfinite_weights" in model.contents:
            warnings.warn("%s: the weights are not finite: the run that "
                          "trained it diverged; it loads for inspection "
                          "(Model.query), but renderers, trainers, meshes "
                          "and saves refuse it" % os.fsdecode(path),
                          RuntimeWarning, stacklevel=2)
        return model

    @classmethod
    def import_npz(cls, path: Any, preset: Union[str, int, None] = None,
                   seed: int = 0, *, log: LogFn = None,
                   log_level: Optional[int] = None,
                   **options: Any) -> "Model":
        """A model with the given options whose weights come from a NumPy
        ``.npz`` state dict of the reference implementation
        (``nerf_model_import_npz``; see docs/formats.md)."""
        opts = model_options(preset, seed, **options)
        hooks = _handle.make_hooks(log, log_level)
        if hooks is not None:
            opts.hooks = ctypes.pointer(hooks[0])
        res = _handle.create("Model", ModelP, lib.nerf_model_import_npz,
                             _handle.destroyer("nerf_model_destroy"),
                             _handle.fspath(path), ctypes.byref(opts),
                             keep=hooks[1] if hooks else None)
        return cls._wrap(res)

    def save(self, path: Any) -> None:
        """Write a checkpoint (weights, optimiser state and step),
        atomically replacing ``path`` (``nerf_model_save``).  A model loaded
        from a weights-only export is saved weights-only again."""
        with self._using() as ptr:
            lib.nerf_model_save(ptr, _handle.fspath(path))

    def export(self, path: Any) -> None:
        """Write the weights without the optimiser state
        (``nerf_model_export``): under half a checkpoint, for sharing,
        rendering and evaluating.  :meth:`load` reads it; a
        :class:`nerf.Trainer` refuses the model it gives."""
        with self._using() as ptr:
            lib.nerf_model_export(ptr, _handle.fspath(path))

    @property
    def contents(self) -> FrozenSet[str]:
        """What the model holds beyond its weights
        (``nerf_model_contents``): ``"optimizer"`` (training can resume;
        absent for a weights-only export), ``"occupancy"`` (a trained
        occupancy grid), ``"render_settings"`` (recorded by training),
        ``"data_record"`` (what data training last used:
        :attr:`training_data`), ``"batch_record"`` (the batch it used:
        :attr:`training_batch`), ``"adam_corrections"`` (a hash-grid
        model's Adam corrections of each table parameter by its own count
        of updates, since 0.10; without them such a model from an older
        file corrects by the step), ``"nonfinite_weights"`` (weights that
        are NaN or infinite: a run that diverged; see :meth:`load`),
        ``"appearance"`` (per-image appearance codes, since 0.13:
        :meth:`appearance_code`)."""
        with self._using() as ptr:
            bits = int(lib.nerf_model_contents(ptr))
        return frozenset(name for bit, name in CONTENTS.items() if bits & bit)

    @property
    def training_data(self) -> str:
        """One line on the data a trainer last trained the model on
        (``nerf_model_training_data``): image count and size, format, mean
        colour and bounds; "" when nothing is recorded."""
        buf = ctypes.create_string_buffer(512)
        with self._using() as ptr:
            lib.nerf_model_training_data(ptr, buf, len(buf))
        return buf.value.decode("utf-8", "replace")

    @property
    def training_batch(self) -> Optional[Tuple[int, int]]:
        """``(batch_rays, batch_samples)`` of the trainer that last
        trained the model (``nerf_model_training_batch``), or None when
        nothing is recorded.  A resumed run goes on bit for bit only at
        the batch it began with: give these to the :class:`Trainer`."""
        rays, samples = ctypes.c_uint32(0), ctypes.c_uint32(0)
        with self._using() as ptr:
            lib.nerf_model_training_batch(ptr, ctypes.byref(rays),
                                          ctypes.byref(samples))
        return (rays.value, samples.value) if rays.value else None

    @property
    def appearance_count(self) -> int:
        """How many per-image appearance codes the model holds
        (``nerf_model_appearance_count``): the training images of a
        trainer with ``appearance_codes=1``, 0 for a model without."""
        n = ctypes.c_uint32(0)
        with self._using() as ptr:
            lib.nerf_model_appearance_count(ptr, ctypes.byref(n))
        return n.value

    def appearance_code(self, image: Optional[int] = None
                        ) -> Tuple[float, float, float]:
        """The appearance code of training image ``image``, or the neutral
        one (the mean of all) when None (``nerf_model_appearance_code``):
        the natural logarithms of the red, green and blue gains."""
        which = APPEARANCE_NEUTRAL if image is None else appearance_of(image)
        code = (ctypes.c_float * APPEARANCE_CODE_FLOATS)()
        with self._using() as ptr:
            lib.nerf_model_appearance_code(ptr, which, code)
        return tuple(float(v) for v in code)  # type: ignore[return-value]

    @property
    def schedule(self) -> dict:
        """How the learning-rate schedule came about
        (``nerf_model_schedule``): ``state`` ("steps", "measuring" or
        "fitted"), ``budget_seconds``, ``steps_per_second``, ``fit_step``
        and ``total_steps`` (the step a budget's run, or a ``--steps`` run,
        ends at)."""
        sc = ScheduleStruct()
        with self._using() as ptr:
            lib.nerf_model_schedule(ptr, ctypes.byref(sc))
        states = ("steps", "measuring", "fitted")
        return {
            "state": states[sc.state] if sc.state < 3 else int(sc.state),
            "budget_seconds": sc.budget_seconds,
            "steps_per_second": sc.steps_per_second,
            "fit_step": int(sc.fit_step),
            "total_steps": int(sc.total_steps),
        }

    def render_settings(self) -> Tuple[SamplerOptions, RendererOptions]:
        """``(SamplerOptions, RendererOptions)`` to render the model with
        (``nerf_model_render_settings``): those its training recorded, or
        for a model without them a guess from its shape (Blender-like
        near 2, far 6 on white for a box model).  :class:`nerf.Renderer`
        uses them when given no sampler."""
        so, ro = SamplerOptions(), RendererOptions()
        with self._using() as ptr:
            lib.nerf_model_render_settings(ptr, ctypes.byref(so),
                                           ctypes.byref(ro))
        return so, ro

    def set_render_settings(self, sampler: Any,
                            white_background: int) -> None:
        """Record what rendering the model needs
        (``nerf_model_set_render_settings``): the sampling fields of
        ``sampler`` (a :class:`nerf.Sampler` or :class:`SamplerOptions`)
        and the background (1 white, 0 black).  A :class:`nerf.Trainer`
        records its own; checkpoints and exports keep them."""
        opts = getattr(sampler, "options", sampler)
        if not isinstance(opts, SamplerOptions):
            raise TypeError("sampler must be a nerf.Sampler or "
                            "nerf.SamplerOptions")
        with self._using() as ptr:
            lib.nerf_model_set_render_settings(
                ptr, ctypes.byref(opts),
                integer(white_background, "white_background"))

    @property
    def options(self) -> ModelOptions:
        """A copy of the model's options (``hooks`` is always NULL)."""
        opts = ModelOptions()
        with self._using() as ptr:
            lib.nerf_model_get_options(ptr, ctypes.byref(opts))
        return opts

    @property
    def param_count(self) -> int:
        """Number of trainable parameters of both networks."""
        with self._using() as ptr:
            return int(lib.nerf_model_param_count(ptr))

    @property
    def step(self) -> int:
        """Optimisation steps taken so far."""
        with self._using() as ptr:
            return int(lib.nerf_model_step(ptr))

    @property
    def learning_rate(self) -> float:
        """The learning rate the schedule gives at the current step."""
        with self._using() as ptr:
            return float(lib.nerf_model_learning_rate(ptr))

    def set_param(self, param: Union[str, int], value: float) -> None:
        """Set a training hyperparameter by name ("learning_rate",
        "learning_rate_final", "decay_steps", "adam_beta1", "adam_beta2",
        "adam_eps", "weight_decay") or number (``nerf.PARAM_*``)."""
        with self._using() as ptr:
            lib.nerf_model_set_param(ptr, param_key(param), float(value))

    def get_param(self, param: Union[str, int]) -> float:
        """Read a training hyperparameter (see :meth:`set_param`)."""
        value = ctypes.c_double()
        with self._using() as ptr:
            lib.nerf_model_get_param(ptr, param_key(param),
                                     ctypes.byref(value))
        return value.value

    def query(self, positions: Any, directions: Any = None,
              network: Union[str, int, None] = None) -> Tuple[Any, Any]:
        """Evaluate one network at ``n`` points (``nerf_model_query``).

        Args:
            positions: n x 3 floats (or 3 n flat).
            directions: n x 3 unit view directions, the same shape as
                positions, or None when the model does not use view
                directions.
            network: "coarse", "fine" or 0 / 1; by default the fine
                network when the model has one, else the coarse one.

        Returns:
            ``(rgb, sigma)``: n x 3 colours in [0, 1] and n raw densities.
        """
        pos = _buffers.as_float_input(positions, "positions",
                                      shape=(None, 3))
        n = pos.shape[0]
        dirs = None
        if directions is not None:
            dirs = _buffers.as_float_input(directions, "directions",
                                           shape=(n, 3))
        if network is None:
            network = NETWORK_FINE if self.options.use_fine else NETWORK_COARSE
        rgb = _buffers.FloatOutput((n, 3), "rgb")
        sigma = _buffers.FloatOutput((n,), "sigma")
        with self._using() as ptr:
            lib.nerf_model_query(ptr, network_key(network), n, pos.ptr,
                                 dirs.ptr if dirs else None, rgb.ptr,
                                 sigma.ptr)
        return rgb.release(), sigma.release()

    def mesh(self, resolution: int = 256, threshold: float = 25.0,
             box: Optional[Any] = None, colour: bool = True,
             keep_largest: bool = False, min_component_faces: int = 0,
             threads: int = 0, progress: Any = None) -> Any:
        """The surface where the density crosses ``threshold``, by
        marching cubes over a grid of ``resolution`` cells along the
        longest side of ``box`` (x0, y0, z0, x1, y1, z1; None: the model's
        bounds) (``nerf_mesh_extract``, since libnerf 0.5).

        ``colour``: vertex colours as seen looking at the surface head on.
        ``keep_largest``: only the connected piece with the most faces;
        ``min_component_faces``: drop smaller pieces.  ``progress(p)`` is
        called after each plane of samples; a true return cancels
        (NerfCancelled).

        Returns:
            a :class:`nerf.Mesh` with ``vertices``, ``faces``, ``normals``
            and ``colours`` arrays and ``write(path)``.
        """
        from . import mesh as _mesh
        opts = _mesh.mesh_options(
            resolution=resolution, threshold=threshold, box=box,
            colour=colour, keep_largest=keep_largest,
            min_component_faces=min_component_faces, threads=threads)
        with self._using() as ptr:
            return _mesh.extract(self._res, ptr, opts, progress)

    def write_density_grid(self, path: Any, resolution: int = 256,
                           box: Optional[Any] = None, colour: bool = False,
                           threads: int = 0, progress: Any = None) -> Any:
        """Write the density at the cell centres of a grid over ``box`` as
        a float32 .npy of shape (nz, ny, nx), with a JSON sidecar (``path``
        with .json for .npy) recording the box; with ``colour``, colours
        in ``*_rgb.npy`` too (``nerf_density_grid_write``, since 0.5).

        Returns:
            the sidecar, as a dict ("shape", "box_min", "box_max",
            "spacing", "order", ...).
        """
        from . import mesh as _mesh
        opts = _mesh.mesh_options(resolution=resolution, box=box,
                                  colour=colour, threads=threads)
        with self._using() as ptr:
            return _mesh.write_grid(ptr, path, opts, progress)
