"""``nerf.Trainer``: the optimisation loop."""

from __future__ import annotations

import ctypes
from typing import Any, Callable, Optional

from . import _handle
from ._capi import TrainerP, lib
from .data import Dataset
from .model import Model
from .render import Sampler
from .structs import (Progress, TrainerOptions, TrainStats, TrainStatsStruct,
                      c_uint64, integer)

LogFn = Optional[Callable[[int, str], Any]]
ProgressFn = Optional[Callable[[Progress], Any]]


class Trainer(_handle.ProgressHandle):
    """Optimises a model on a dataset's images (``nerf_trainer``).

    ``Trainer(model, dataset, sampler, batch_rays=1024, ...)``; keyword
    options are fields of :class:`nerf.TrainerOptions` (``checkpoint_path``
    may be a str or path), for example ``random_background=1`` to train a
    Blender scene's rays against random background colours (as instant-ngp
    does; images without alpha ignore it).  The trainer keeps the model,
    dataset and sampler alive; nothing else may use the model while a step
    runs.

    ``progress``: the default callback of :meth:`run`, called after every
    step with a :class:`nerf.Progress`; a true return value cancels.
    """

    _kind = "Trainer"

    def __init__(self, model: Model, dataset: Dataset, sampler: Sampler, *,
                 progress: ProgressFn = None, log: LogFn = None,
                 log_level: Optional[int] = None, **options: Any) -> None:
        if not isinstance(model, Model):
            raise TypeError("model must be a nerf.Model")
        if not isinstance(dataset, Dataset):
            raise TypeError("dataset must be a nerf.Dataset")
        if not isinstance(sampler, Sampler):
            raise TypeError("sampler must be a nerf.Sampler")
        opts = TrainerOptions(**options)
        hooks = _handle.make_hooks(log, log_level)
        if hooks is not None:
            opts.hooks = ctypes.pointer(hooks[0])
        self._slot = _handle.ProgressSlot("Trainer")
        self._slot.callback = progress
        keep = [self._slot.thunk] + (list(hooks[1]) if hooks else [])
        with model._using() as mp, dataset._using() as dp, \
                sampler._using() as sp:
            res = _handle.create(
                "Trainer", TrainerP, lib.nerf_trainer_create,
                _handle.destroyer("nerf_trainer_destroy"), mp, dp, sp,
                ctypes.byref(opts),
                deps=(model._res, dataset._res, sampler._res), keep=keep)
        super().__init__(res)
        self.model = model
        self.dataset = dataset
        self.sampler = sampler
        with self._using() as ptr:
            lib.nerf_trainer_set_progress(ptr, self._slot.thunk, None)

    @classmethod
    def for_model(cls, model: Model, dataset: Dataset,
                  sampler: Optional[Sampler] = None, *, seed: int = 0,
                  progress: ProgressFn = None, log: LogFn = None,
                  log_level: Optional[int] = None,
                  **options: Any) -> "Trainer":
        """The trainer ``nerf-train`` makes for ``model`` on ``dataset``:
        the sampler of :meth:`nerf.Sampler.for_model` with
        ``training=True`` (when none is given) and the options of
        ``nerf_trainer_options_for`` (the batch the model was trained at
        or its preset's; no crop and a random background for a hash-grid
        model, with the finer march it records; with a
        ``checkpoint_path`` and no ``checkpoint_every``, a save every two
        minutes).  ``options`` override any field.  With a model from
        :meth:`nerf.Model.for_dataset` (``matmul="fp32-fastest"``) whose
        ``NERF_PARAM_DECAY_STEPS`` is the run's length, the checkpoint it
        writes is ``nerf-train``'s, bit for bit."""
        if sampler is None:
            sampler = Sampler.for_model(model, dataset, training=True,
                                        seed=seed)
        opts = TrainerOptions()
        opts.update(**{k: options.pop(k) for k in
                       ("checkpoint_path", "checkpoint_every")
                       if k in options})
        with model._using() as mp:
            lib.nerf_trainer_options_for(ctypes.byref(opts), mp)
        fields = opts.to_dict()
        fields.update(options)
        return cls(model, dataset, sampler, progress=progress, log=log,
                   log_level=log_level, **fields)

    def step(self) -> TrainStats:
        """Take one optimisation step and return its figures
        (``nerf_trainer_step``).  A non-finite loss raises
        NerfInternalError ("training diverged"), saying whether the weights
        are still finite, and leaves them as they were before the step.
        A model whose weights are not finite is refused by the trainer, by
        renderers and by :meth:`nerf.Model.save`."""
        stats = TrainStatsStruct()
        with self._using() as ptr:
            self._slot.run(lib.nerf_trainer_step, ptr, ctypes.byref(stats))
        return TrainStats.from_struct(stats)

    def run(self, n_steps: int, progress: ProgressFn = None) -> TrainStats:
        """Take ``n_steps`` steps (``nerf_trainer_run``), calling
        ``progress`` (or the trainer's default callback) after each, and
        saving checkpoints as the options say.

        Returns the figures of the last step.  Raises NerfCancelled when the
        callback returned a true value or :meth:`cancel` was called (after a
        whole step), and re-raises whatever the callback raised (Ctrl-C
        included) once the current step is done.
        """
        stats = TrainStatsStruct()
        with self._using() as ptr:
            self._slot.run(lib.nerf_trainer_run, ptr,
                           integer(n_steps, "run: n_steps", c_uint64),
                           ctypes.byref(stats), progress=progress)
        return TrainStats.from_struct(stats)

    def run_for(self, seconds: float,
                progress: ProgressFn = None) -> TrainStats:
        """Train for about ``seconds`` of wall time, the learning rate
        decaying over the steps that time allows (``nerf_trainer_run_for``):
        the rate holds for the first quarter while the step rate is
        measured, then the run's length is fixed and recorded in the model
        (:attr:`nerf.Model.schedule`), so that a saved model resumes bit for
        bit; at a half, three quarters and nine tenths of the time (or
        when the run reaches it before) the length is fitted again to the
        rate then.  A model already fitted
        trains on to its recorded length.

        Returns the figures of the last step.  Raises NerfCancelled when the
        callback or :meth:`cancel` stopped the run, or when the steps ran so
        much slower than measured that a tenth past ``seconds`` passed (a
        later call trains on to the recorded length).
        """
        stats = TrainStatsStruct()
        with self._using() as ptr:
            self._slot.run(lib.nerf_trainer_run_for, ptr, float(seconds),
                           ctypes.byref(stats), progress=progress)
        return TrainStats.from_struct(stats)

    def cancel(self) -> None:
        """Ask a running :meth:`run` to stop after its current step.
        Thread-safe; a no-op when nothing runs or the trainer is closed."""
        try:
            ptr = self._res.acquire()
        except ValueError:
            return
        try:
            lib.nerf_trainer_cancel(ptr)
        finally:
            self._res.release()
