"""Prototypes of every public libnerf function.

Importing this module loads the library (see :mod:`nerf._loader`), checks
its major version and gives every function of ``nerf.h`` its ``argtypes``
and ``restype``.  Functions that return a status get
:func:`nerf.errors.check_status` as ``errcheck``, so a negative status
raises :class:`nerf.NerfError` with the library's message.

Handles are typed opaque pointers (``ModelP`` and so on), so passing a
sampler where a model is expected fails in ctypes rather than in C.
"""

from __future__ import annotations

import ctypes
from ctypes import (POINTER, c_char_p, c_double, c_float, c_int, c_size_t,
                    c_uint, c_uint8, c_uint32, c_uint64, c_void_p)

from . import _loader, errors
from .structs import (LOG_CB, PROGRESS_CB, BakeOptions, BakeStats,
                      Camera, CameraPathOptions,
                      DatasetOptions, Hooks, MeshOptions, ModelOptions,
                      PointsOptions, RendererOptions, SamplerOptions,
                      SceneOptions, ScheduleStruct, TrainerOptions,
                      TrainStatsStruct)


class _Opaque(ctypes.Structure):
    """Base of the incomplete C handle types."""
    _fields_ = []


class nerf_model(_Opaque):
    pass


class nerf_sampler(_Opaque):
    pass


class nerf_renderer(_Opaque):
    pass


class nerf_dataset(_Opaque):
    pass


class nerf_trainer(_Opaque):
    pass


class nerf_camera_path(_Opaque):
    pass


class nerf_points(_Opaque):
    pass


class nerf_mesh(_Opaque):
    pass


class nerf_bake(_Opaque):
    pass


ModelP = POINTER(nerf_model)
SamplerP = POINTER(nerf_sampler)
RendererP = POINTER(nerf_renderer)
DatasetP = POINTER(nerf_dataset)
TrainerP = POINTER(nerf_trainer)
CameraPathP = POINTER(nerf_camera_path)
PointsP = POINTER(nerf_points)
MeshP = POINTER(nerf_mesh)
BakeP = POINTER(nerf_bake)

_F = POINTER(c_float)
_D = POINTER(c_double)
_U32 = POINTER(c_uint32)

# name: (restype, argtypes, returns a status?)
_PROTOTYPES = {
    # Errors and versions.
    "nerf_status_string": (c_char_p, [c_int], False),
    "nerf_last_error": (c_char_p, [], False),
    "nerf_clear_error": (None, [], False),
    "nerf_version_number": (c_uint, [], False),
    "nerf_version_string": (c_char_p, [], False),
    "nerf_build_info": (c_char_p, [], False),
    # Logging and hooks.
    "nerf_log_set_default": (None, [LOG_CB, c_void_p, c_int], False),
    "nerf_log_stderr": (None, [c_int, c_char_p, c_void_p], False),
    "nerf_hooks_init": (c_int, [POINTER(Hooks), c_size_t], True),
    # Model.
    "nerf_model_options_init": (c_int, [POINTER(ModelOptions), c_size_t],
                                True),
    "nerf_model_options_preset": (c_int, [POINTER(ModelOptions), c_int], True),
    "nerf_model_options_for_dataset": (c_int, [POINTER(ModelOptions),
                                               DatasetP], True),
    "nerf_model_create": (c_int, [POINTER(ModelP), POINTER(ModelOptions)],
                          True),
    "nerf_model_destroy": (None, [ModelP], False),
    "nerf_model_get_options": (c_int, [ModelP, POINTER(ModelOptions)], True),
    "nerf_model_param_count": (c_size_t, [ModelP], False),
    "nerf_model_step": (c_uint64, [ModelP], False),
    "nerf_model_query": (c_int, [ModelP, c_int, c_size_t, _F, _F, _F, _F],
                         True),
    "nerf_param_bounds": (c_int, [c_int, _D, _D], True),
    "nerf_model_set_param": (c_int, [ModelP, c_int, c_double], True),
    "nerf_model_get_param": (c_int, [ModelP, c_int, _D], True),
    "nerf_model_learning_rate": (c_double, [ModelP], False),
    "nerf_model_save": (c_int, [ModelP, c_char_p], True),
    "nerf_model_load": (c_int, [POINTER(ModelP), c_char_p, POINTER(Hooks)],
                        True),
    "nerf_model_import_npz": (c_int, [POINTER(ModelP), c_char_p,
                                      POINTER(ModelOptions)], True),
    "nerf_matmul_supported": (c_int, [c_int], False),
    # Since 0.4: weights-only exports and render settings.
    "nerf_model_export": (c_int, [ModelP, c_char_p], True),
    "nerf_model_contents": (c_uint32, [ModelP], False),
    "nerf_model_training_data": (c_int, [ModelP, c_char_p, c_size_t], True),
    "nerf_model_set_render_settings": (c_int, [ModelP,
                                               POINTER(SamplerOptions),
                                               c_uint32], True),
    "nerf_model_render_settings": (c_int, [ModelP, POINTER(SamplerOptions),
                                           POINTER(RendererOptions)], True),
    # Since 0.5: schedules fitted to a time budget.
    "nerf_model_schedule": (c_int, [ModelP, POINTER(ScheduleStruct)], True),
    # Since 0.8: the batch a trainer recorded.
    "nerf_model_training_batch": (c_int, [ModelP, _U32, _U32], True),
    # Since 0.13: per-image appearance codes.
    "nerf_model_appearance_count": (c_int, [ModelP, _U32], True),
    "nerf_model_appearance_code": (c_int, [ModelP, c_uint32, _F], True),
    # Since 0.14: baked models.
    "nerf_bake_options_init": (c_int, [POINTER(BakeOptions), c_size_t], True),
    "nerf_bake_create": (c_int, [POINTER(BakeP), ModelP,
                                 POINTER(BakeOptions)], True),
    "nerf_bake_destroy": (None, [BakeP], False),
    "nerf_bake_stats_get": (c_int, [BakeP, POINTER(BakeStats)], True),
    "nerf_bake_render_image": (c_int, [BakeP, POINTER(Camera), _F, _F, _F,
                                       c_size_t], True),
    # Since 0.5: meshes and density grids.
    "nerf_mesh_options_init": (c_int, [POINTER(MeshOptions), c_size_t], True),
    "nerf_mesh_extract": (c_int, [POINTER(MeshP), ModelP,
                                  POINTER(MeshOptions)], True),
    "nerf_mesh_destroy": (None, [MeshP], False),
    "nerf_mesh_vertex_count": (c_size_t, [MeshP], False),
    "nerf_mesh_face_count": (c_size_t, [MeshP], False),
    "nerf_mesh_vertices": (_F, [MeshP], False),
    "nerf_mesh_faces": (_U32, [MeshP], False),
    "nerf_mesh_normals": (_F, [MeshP], False),
    "nerf_mesh_colours": (POINTER(c_uint8), [MeshP], False),
    "nerf_mesh_write": (c_int, [MeshP, c_char_p, c_int], True),
    "nerf_density_grid_write": (c_int, [ModelP, c_char_p,
                                        POINTER(MeshOptions)], True),
    # Built-in scene.
    "nerf_scene_options_init": (c_int, [POINTER(SceneOptions), c_size_t],
                                True),
    "nerf_scene_write": (c_int, [c_char_p, POINTER(SceneOptions)], True),
    # Cameras.
    "nerf_camera_init": (c_int, [POINTER(Camera), c_size_t], True),
    "nerf_camera_rays": (c_int, [POINTER(Camera), c_size_t, c_size_t, _F, _F],
                         True),
    "nerf_camera_look_at": (c_int, [POINTER(Camera), _F, _F, _F], True),
    "nerf_camera_path_options_init": (c_int, [POINTER(CameraPathOptions),
                                              c_size_t], True),
    "nerf_camera_path_load": (c_int, [POINTER(CameraPathP), c_char_p,
                                      POINTER(CameraPathOptions)], True),
    "nerf_camera_path_destroy": (None, [CameraPathP], False),
    "nerf_camera_path_count": (c_uint32, [CameraPathP], False),
    "nerf_camera_path_camera": (c_int, [CameraPathP, c_uint32,
                                        POINTER(Camera)], True),
    # Sampler.
    "nerf_sampler_options_init": (c_int, [POINTER(SamplerOptions), c_size_t],
                                  True),
    "nerf_sampler_options_preset": (c_int, [POINTER(SamplerOptions), c_int],
                                    True),
    "nerf_sampler_options_set_march": (c_int, [POINTER(SamplerOptions),
                                               c_uint32], True),
    "nerf_sampler_options_for": (c_int, [POINTER(SamplerOptions), ModelP,
                                         DatasetP, c_int], True),
    "nerf_sampler_create": (c_int, [POINTER(SamplerP),
                                    POINTER(SamplerOptions)], True),
    "nerf_sampler_destroy": (None, [SamplerP], False),
    "nerf_sampler_sample_coarse": (c_int, [SamplerP, c_size_t, c_uint32,
                                           c_uint64, _F, _F], True),
    "nerf_sampler_sample_fine": (c_int, [SamplerP, c_size_t, c_uint32,
                                         c_uint64, _F, _F, _F, _F], True),
    # Renderer.
    "nerf_renderer_options_init": (c_int, [POINTER(RendererOptions),
                                           c_size_t], True),
    "nerf_renderer_create": (c_int, [POINTER(RendererP), ModelP, SamplerP,
                                     POINTER(RendererOptions)], True),
    "nerf_renderer_destroy": (None, [RendererP], False),
    "nerf_renderer_set_progress": (c_int, [RendererP, PROGRESS_CB, c_void_p],
                                   True),
    "nerf_renderer_cancel": (None, [RendererP], False),
    "nerf_renderer_render_image": (c_int, [RendererP, POINTER(Camera), _F, _F,
                                           _F, c_size_t], True),
    "nerf_renderer_render_image_u8": (c_int, [RendererP, POINTER(Camera),
                                              POINTER(c_uint8), _F, _F,
                                              c_size_t], True),
    "nerf_renderer_render_rays": (c_int, [RendererP, c_size_t, _F, _F, _F, _F,
                                          _F], True),
    # Point clouds and depth (libnerf 0.5).
    "nerf_renderer_render_depth": (c_int, [RendererP, POINTER(Camera), _F,
                                           _F, _F, _F, c_size_t], True),
    "nerf_npy_write_float": (c_int, [c_char_p, _F, POINTER(c_size_t),
                                     c_uint32], True),
    "nerf_points_options_init": (c_int, [POINTER(PointsOptions), c_size_t],
                                 True),
    "nerf_points_from_views": (c_int, [POINTER(PointsP), RendererP,
                                       POINTER(Camera), c_size_t,
                                       POINTER(PointsOptions)], True),
    "nerf_points_count": (c_size_t, [PointsP], False),
    "nerf_points_arrays": (c_int, [PointsP, POINTER(_F),
                                   POINTER(POINTER(c_uint8)), POINTER(_F)],
                           True),
    "nerf_points_write": (c_int, [PointsP, c_char_p, c_int], True),
    "nerf_points_destroy": (None, [PointsP], False),
    # Images and metrics.
    "nerf_image_read": (c_int, [c_char_p, _U32, _U32, POINTER(_F)], True),
    "nerf_image_read_png": (c_int, [c_char_p, _U32, _U32, POINTER(_F)], True),
    "nerf_image_write_png": (c_int, [c_char_p, c_uint32, c_uint32, c_uint32,
                                     _F], True),
    "nerf_image_write_png8": (c_int, [c_char_p, c_uint32, c_uint32, c_uint32,
                                      POINTER(c_uint8)], True),
    "nerf_free": (None, [c_void_p], False),
    "nerf_psnr": (c_int, [_F, _F, c_size_t, _D], True),
    "nerf_ssim": (c_int, [_F, _F, c_uint32, c_uint32, c_uint32, _D], True),
    "nerf_psnr_masked": (c_int, [_F, _F, POINTER(c_uint8), c_size_t,
                                 c_uint32, _D], True),
    "nerf_ssim_masked": (c_int, [_F, _F, POINTER(c_uint8), c_uint32,
                                 c_uint32, c_uint32, _D], True),
    # Datasets.
    "nerf_dataset_options_init": (c_int, [POINTER(DatasetOptions), c_size_t],
                                  True),
    "nerf_dataset_load": (c_int, [POINTER(DatasetP), c_char_p,
                                  POINTER(DatasetOptions)], True),
    "nerf_dataset_destroy": (None, [DatasetP], False),
    "nerf_dataset_count": (c_uint32, [DatasetP], False),
    "nerf_dataset_get_format": (c_int, [DatasetP], False),
    "nerf_dataset_image_size": (c_int, [DatasetP, _U32, _U32], True),
    "nerf_dataset_image": (c_int, [DatasetP, c_uint32, POINTER(_F)], True),
    "nerf_dataset_has_masks": (c_int, [DatasetP], False),
    "nerf_dataset_mask": (c_int, [DatasetP, c_uint32,
                                  POINTER(POINTER(c_uint8))], True),
    "nerf_dataset_camera": (c_int, [DatasetP, c_uint32, POINTER(Camera)],
                            True),
    "nerf_dataset_bounds": (c_int, [DatasetP, _F, _F], True),
    "nerf_dataset_is_ndc": (c_int, [DatasetP], False),
    "nerf_dataset_space": (c_int, [DatasetP, _U32, _F], True),
    "nerf_dataset_spiral_camera": (c_int, [DatasetP, c_uint32, c_uint32,
                                           POINTER(Camera)], True),
    # Training.
    "nerf_trainer_options_init": (c_int, [POINTER(TrainerOptions), c_size_t],
                                  True),
    "nerf_trainer_options_for": (c_int, [POINTER(TrainerOptions), ModelP],
                                 True),
    "nerf_trainer_create": (c_int, [POINTER(TrainerP), ModelP, DatasetP,
                                    SamplerP, POINTER(TrainerOptions)], True),
    "nerf_trainer_destroy": (None, [TrainerP], False),
    "nerf_trainer_step": (c_int, [TrainerP, POINTER(TrainStatsStruct)], True),
    "nerf_trainer_run": (c_int, [TrainerP, c_uint64,
                                 POINTER(TrainStatsStruct)], True),
    "nerf_trainer_set_progress": (c_int, [TrainerP, PROGRESS_CB, c_void_p],
                                  True),
    "nerf_trainer_cancel": (None, [TrainerP], False),
    "nerf_trainer_run_for": (c_int, [TrainerP, c_double,
                                     POINTER(TrainStatsStruct)], True),
}


class _Api:
    """The loaded library's functions, as attributes named as in C."""

    def __init__(self, cdll: ctypes.CDLL, where: str) -> None:
        self.cdll = cdll
        self.path = where
        missing = []
        for name, (restype, argtypes, checked) in _PROTOTYPES.items():
            try:
                fn = getattr(cdll, name)
            except AttributeError:
                missing.append(name)
                continue
            fn.restype = restype
            fn.argtypes = argtypes
            if checked:
                fn.errcheck = errors.check_status
            setattr(self, name, fn)
        if missing:
            raise ImportError(
                "libnerf: %s lacks %s; it is older than this binding "
                "expects. Set NERF_LIBRARY to a matching libnerf."
                % (where, ", ".join(sorted(missing))))


def _load() -> _Api:
    cdll, where = _loader.find_and_load()
    try:
        version = cdll.nerf_version_number
    except AttributeError:
        raise ImportError("libnerf: %s has no nerf_version_number(); it is "
                          "not a libnerf shared library. Set NERF_LIBRARY to "
                          "libnerf.so.0." % where) from None
    version.restype = c_uint
    version.argtypes = []
    _loader.check_version(version(), where)
    api = _Api(cdll, where)
    errors._status_string_fn = api.nerf_status_string
    errors._last_error_fn = api.nerf_last_error
    return api


#: The library, loaded once on import.
lib = _load()

#: Every C function this module declares (for the coverage test).
FUNCTION_NAMES = tuple(_PROTOTYPES)
