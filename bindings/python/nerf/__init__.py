"""Python binding of libnerf: Neural Radiance Fields on the CPU.

A pure ctypes package: nothing is compiled.  Importing it loads the libnerf
shared library (``NERF_LIBRARY``, then the installed library, then a build
directory of this source tree; see :mod:`nerf._loader`) and checks that its
major version is the one this binding speaks.

Quick tour::

    import nerf

    nerf.write_scene("scene", width=64, height=64, n_train=20)
    train = nerf.Dataset("scene", "train")
    with nerf.Model(preset="tiny", seed=0) as model:
        sampler = nerf.Sampler.for_dataset(train, preset="tiny")
        trainer = nerf.Trainer(model, train, sampler, batch_rays=512)
        stats = trainer.run(200, progress=lambda p: print(p.done, p.psnr))
        renderer = nerf.Renderer(model, sampler, white_background=1)
        image = renderer.render_image(train.camera(0)).rgb
        nerf.write_png("view.png", image)

Errors raise :class:`NerfError` subclasses carrying the library's message
and status code.  Handles (:class:`Model`, :class:`Sampler`,
:class:`Renderer`, :class:`Dataset`, :class:`Trainer`) have an idempotent
``close()``, work as context managers, and may be closed or collected in
any order: a handle's C object is destroyed only once no dependent handle
uses it (see :mod:`nerf._handle`).  Arrays are NumPy arrays when NumPy is
installed and memoryviews otherwise (see :mod:`nerf._buffers`).
"""

from ._buffers import HAVE_NUMPY
from ._loader import EXPECTED_MAJOR
from .core import (LOG_DEBUG, LOG_ERROR, LOG_INFO, LOG_WARN, PARAMS,
                   PARAM_ADAM_BETA1, PARAM_ADAM_BETA2, PARAM_ADAM_EPS,
                   PARAM_WEIGHT_DECAY, PARAM_DECAY_STEPS, PARAM_DECAY_START,
                   PARAM_AVERAGE_STEPS, PARAM_LEARNING_RATE,
                   PARAM_LEARNING_RATE_FINAL, build_info, clear_error,
                   last_error, library_path, log_stderr, log_to_stderr,
                   param_bounds, set_log_handler, status_string, version,
                   version_number, version_string)
from .data import (CAMERA_PATH_FILE_INTRINSICS, CAMERA_PATH_FILE_SIZE,
                   DATASET_BLENDER, DATASET_COLMAP, DATASET_LLFF,
                   IMAGE_FORMAT_JPEG, IMAGE_FORMAT_PNG, IMAGE_MAX_SIDE,
                   SCENE_CAPTURE_FORWARD, SCENE_CAPTURE_OBJECT,
                   SCENE_CAPTURE_UNBOUNDED, SCENE_CAPTURE_WALK,
                   SCENE_LAYOUT_BLENDER,
                   SCENE_APPEARANCE_CONSTANT, SCENE_APPEARANCE_VARIED,
                   SCENE_LAYOUT_COLMAP_BINARY, SCENE_LAYOUT_COLMAP_TEXT,
                   SCENE_LAYOUT_LLFF, SCENE_LAYOUT_TRANSFORMS,
                   SCENE_MAX_SIDE, SCENE_MAX_VIEWS, SCENE_MIN_SIDE, SPLIT_TEST,
                   SPLIT_TRAIN, SPLIT_VAL, Dataset, load_camera_path, psnr,
                   read_image, read_png, ssim, write_npy, write_png,
                   write_scene)
from .errors import (ECANCELLED, EFORMAT, EINVAL, EIO, ENOMEM, ERROR,
                     EVERSION, OK, NerfCancelled, NerfError, NerfFormatError,
                     NerfInternalError, NerfInvalidArgument, NerfIOError,
                     NerfNoMemory, NerfVersionError)
from .errors import ENOENT, EUNRECOGNISED, NerfNotFound, NerfUnrecognised
from .model import (ENCODING_FREQUENCY, ENCODING_INCLUDE_INPUT,
                    ENCODING_SCALE_PI, NETWORK_COARSE, NETWORK_FINE,
                    PRESET_FAST, PRESET_REFERENCE, PRESET_TINY, Model,
                    ENCODING_HASHGRID, ENCODING_SPHERICAL_HARMONICS,
                    DENSITY_RELU, DENSITY_EXP, MATMUL_BF16, MATMUL_FP32,
                    MATMUL_FP32_ONEDNN, MATMUL_FP32_FASTEST,
                    SPACE_BOX, SPACE_NDC, SPACE_UNBOUNDED,
                    MODEL_HAS_OPTIMIZER, MODEL_HAS_OCCUPANCY,
                    MODEL_HAS_RENDER_SETTINGS, MODEL_HAS_DATA_RECORD,
                    MODEL_HAS_BATCH_RECORD, MODEL_HAS_ADAM_CORRECTIONS,
                    MODEL_HAS_NONFINITE_WEIGHTS, MODEL_HAS_APPEARANCE,
                    APPEARANCE_NEUTRAL, APPEARANCE_CODE_FLOATS,
                    appearance_of, matmul_supported)
from .render import (CAMERA_PIXEL_CORNER, NOISE_AUTO, SAMPLE_TRAINING,
                     SAMPLER_FOR_RENDERING, SAMPLER_FOR_TRAINING,
                     DepthResult, PointCloud, RenderResult, Renderer, Sampler)
from .structs import (PROGRESS_RENDER, PROGRESS_TRAIN, Camera,
                      CameraPathOptions, DatasetOptions, Hooks, ModelOptions,
                      Named, PointsOptions, Progress,
                      ProgressStruct, RendererOptions, SamplerOptions,
                      SceneOptions, TrainerOptions, TrainStats,
                      TrainStatsStruct)
from .train import Trainer
from .bake import Bake
from .mesh import (MESH_COLOUR_NONE, MESH_COLOUR_NORMAL, MESH_FORMAT_AUTO,
                   MESH_FORMAT_OBJ, MESH_FORMAT_PLY, MESH_FORMAT_PLY_ASCII,
                   Mesh)
from .structs import (EXCHANGE_MAX_SPARSE, POINTS_DEFAULT_MAX,
                      POINTS_DEFAULT_OPACITY, POINTS_PLY_ASCII,
                      POINTS_PLY_BINARY, PROGRESS_BAKE, PROGRESS_GEOMETRY,
                      SCHEDULE_FITTED,
                      SCHEDULE_MEASURING, SCHEDULE_STEPS, BakeOptions,
                      MeshOptions)

#: The version of the loaded library, "major.minor.patch".
__version__ = version_string()

__all__ = [
    # Handles and helpers.
    "Model", "Sampler", "Renderer", "Dataset", "Trainer", "Camera",
    "RenderResult", "Progress", "TrainStats", "DepthResult", "PointCloud",
    "Mesh", "MeshOptions", "Bake", "BakeOptions",
    "write_scene", "read_image", "read_png", "write_png", "psnr", "ssim",
    "write_npy",
    "load_camera_path",
    # Option structs.
    "ModelOptions", "SamplerOptions", "RendererOptions", "DatasetOptions",
    "TrainerOptions", "SceneOptions", "CameraPathOptions", "Hooks",
    "ProgressStruct", "TrainStatsStruct", "Named", "PointsOptions",
    # Errors.
    "NerfError", "NerfInternalError", "NerfInvalidArgument", "NerfNoMemory",
    "NerfIOError", "NerfFormatError", "NerfCancelled", "NerfVersionError",
    "OK", "ERROR", "EINVAL", "ENOMEM", "EIO", "EFORMAT", "ECANCELLED",
    "EVERSION", "ENOENT", "EUNRECOGNISED", "NerfNotFound", "NerfUnrecognised",
    # Process-wide functions.
    "version", "version_number", "version_string", "build_info",
    "library_path", "status_string", "last_error", "clear_error",
    "param_bounds", "set_log_handler", "log_to_stderr", "log_stderr",
    "matmul_supported", "appearance_of",
    # Constants.
    "HAVE_NUMPY", "EXPECTED_MAJOR", "LOG_ERROR", "LOG_WARN", "LOG_INFO",
    "LOG_DEBUG", "PARAMS", "PARAM_LEARNING_RATE", "PARAM_LEARNING_RATE_FINAL",
    "PARAM_DECAY_STEPS", "PARAM_ADAM_BETA1", "PARAM_ADAM_BETA2",
    "PARAM_ADAM_EPS", "PARAM_WEIGHT_DECAY", "PARAM_DECAY_START",
    "PARAM_AVERAGE_STEPS", "PRESET_REFERENCE",
    "PRESET_TINY", "PRESET_FAST",
    "ENCODING_HASHGRID", "ENCODING_SPHERICAL_HARMONICS", "DENSITY_RELU",
    "DENSITY_EXP", "MATMUL_FP32", "MATMUL_BF16",
    "MATMUL_FP32_ONEDNN", "MATMUL_FP32_FASTEST", "SPACE_BOX", "SPACE_NDC",
    "SPACE_UNBOUNDED", "MODEL_HAS_OPTIMIZER", "MODEL_HAS_OCCUPANCY",
    "MODEL_HAS_RENDER_SETTINGS", "MODEL_HAS_DATA_RECORD", "NETWORK_COARSE",
    "NETWORK_FINE", "ENCODING_FREQUENCY", "ENCODING_INCLUDE_INPUT",
    "ENCODING_SCALE_PI", "SAMPLE_TRAINING", "SAMPLER_FOR_RENDERING",
    "SAMPLER_FOR_TRAINING", "NOISE_AUTO",
    "CAMERA_PIXEL_CORNER", "PROGRESS_RENDER", "PROGRESS_TRAIN",
    "SPLIT_TRAIN", "SPLIT_VAL", "SPLIT_TEST",
    "DATASET_BLENDER", "DATASET_LLFF", "DATASET_COLMAP", "IMAGE_MAX_SIDE",
    "IMAGE_FORMAT_PNG", "IMAGE_FORMAT_JPEG",
    "SCENE_CAPTURE_OBJECT", "SCENE_CAPTURE_FORWARD",
    "SCENE_CAPTURE_UNBOUNDED", "SCENE_CAPTURE_WALK", "SCENE_LAYOUT_BLENDER",
    "SCENE_LAYOUT_TRANSFORMS", "SCENE_LAYOUT_LLFF",
    "SCENE_LAYOUT_COLMAP_TEXT", "SCENE_LAYOUT_COLMAP_BINARY",
    "CAMERA_PATH_FILE_SIZE", "CAMERA_PATH_FILE_INTRINSICS",
    "MESH_COLOUR_NONE", "MESH_COLOUR_NORMAL", "PROGRESS_GEOMETRY",
    "PROGRESS_BAKE",
    "MODEL_HAS_BATCH_RECORD", "MODEL_HAS_ADAM_CORRECTIONS",
    "MODEL_HAS_NONFINITE_WEIGHTS", "SCENE_MIN_SIDE", "SCENE_MAX_SIDE",
    "SCENE_MAX_VIEWS", "MESH_FORMAT_AUTO", "MESH_FORMAT_PLY",
    "MESH_FORMAT_PLY_ASCII", "MESH_FORMAT_OBJ", "EXCHANGE_MAX_SPARSE",
    "POINTS_DEFAULT_MAX", "POINTS_DEFAULT_OPACITY", "POINTS_PLY_ASCII",
    "POINTS_PLY_BINARY", "SCHEDULE_STEPS", "SCHEDULE_MEASURING",
    "SCHEDULE_FITTED", "MODEL_HAS_APPEARANCE", "APPEARANCE_NEUTRAL",
    "APPEARANCE_CODE_FLOATS", "SCENE_APPEARANCE_CONSTANT",
    "SCENE_APPEARANCE_VARIED",
]

