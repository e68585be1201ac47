"""The ctypes mirrors against the C compiler's view of nerf.h.

Usage: test_layout.py PROBE, where PROBE is the layout_probe program that
meson builds from layout_probe.c; it prints the size of every public
struct and the offset and size of every field, and the public constants.
"""

import ctypes
import json
import subprocess
import sys

import _support
from _support import TestCase, nerf

from nerf import structs

PROBE = None

# Python constants named after the C ones they mirror.
CONSTANTS = {
    "NERF_OK": nerf.OK, "NERF_ERROR": nerf.ERROR, "NERF_EINVAL": nerf.EINVAL,
    "NERF_ENOMEM": nerf.ENOMEM, "NERF_EIO": nerf.EIO,
    "NERF_EFORMAT": nerf.EFORMAT, "NERF_ECANCELLED": nerf.ECANCELLED,
    "NERF_EVERSION": nerf.EVERSION,
    "NERF_ENOENT": nerf.ENOENT, "NERF_EUNRECOGNISED": nerf.EUNRECOGNISED,
    "NERF_VERSION_MAJOR": nerf.EXPECTED_MAJOR,
    "NERF_LOG_ERROR": nerf.LOG_ERROR, "NERF_LOG_WARN": nerf.LOG_WARN,
    "NERF_LOG_INFO": nerf.LOG_INFO, "NERF_LOG_DEBUG": nerf.LOG_DEBUG,
    "NERF_ENCODING_FREQUENCY": nerf.ENCODING_FREQUENCY,
    "NERF_ENCODING_INCLUDE_INPUT": nerf.ENCODING_INCLUDE_INPUT,
    "NERF_ENCODING_SCALE_PI": nerf.ENCODING_SCALE_PI,
    "NERF_PRESET_REFERENCE": nerf.PRESET_REFERENCE,
    "NERF_PRESET_TINY": nerf.PRESET_TINY,
    "NERF_MATMUL_FP32": nerf.MATMUL_FP32,
    "NERF_MATMUL_BF16": nerf.MATMUL_BF16,
    "NERF_MATMUL_FP32_ONEDNN": nerf.MATMUL_FP32_ONEDNN,
    "NERF_SPACE_BOX": nerf.SPACE_BOX,
    "NERF_SPACE_NDC": nerf.SPACE_NDC,
    "NERF_SPACE_UNBOUNDED": nerf.SPACE_UNBOUNDED,
    "NERF_MODEL_HAS_OPTIMIZER": nerf.MODEL_HAS_OPTIMIZER,
    "NERF_MODEL_HAS_OCCUPANCY": nerf.MODEL_HAS_OCCUPANCY,
    "NERF_MODEL_HAS_RENDER_SETTINGS": nerf.MODEL_HAS_RENDER_SETTINGS,
    "NERF_MODEL_HAS_DATA_RECORD": nerf.MODEL_HAS_DATA_RECORD,
    "NERF_NETWORK_COARSE": nerf.NETWORK_COARSE,
    "NERF_NETWORK_FINE": nerf.NETWORK_FINE,
    "NERF_PARAM_LEARNING_RATE": nerf.PARAM_LEARNING_RATE,
    "NERF_PARAM_LEARNING_RATE_FINAL": nerf.PARAM_LEARNING_RATE_FINAL,
    "NERF_PARAM_DECAY_STEPS": nerf.PARAM_DECAY_STEPS,
    "NERF_PARAM_ADAM_BETA1": nerf.PARAM_ADAM_BETA1,
    "NERF_PARAM_ADAM_BETA2": nerf.PARAM_ADAM_BETA2,
    "NERF_PARAM_ADAM_EPS": nerf.PARAM_ADAM_EPS,
    "NERF_CAMERA_PIXEL_CORNER": nerf.CAMERA_PIXEL_CORNER,
    "NERF_SAMPLE_TRAINING": nerf.SAMPLE_TRAINING,
    "NERF_PROGRESS_RENDER": nerf.PROGRESS_RENDER,
    "NERF_PROGRESS_TRAIN": nerf.PROGRESS_TRAIN,
    "NERF_SPLIT_TRAIN": nerf.SPLIT_TRAIN, "NERF_SPLIT_VAL": nerf.SPLIT_VAL,
    "NERF_SPLIT_TEST": nerf.SPLIT_TEST,
    "NERF_DATASET_BLENDER": nerf.DATASET_BLENDER,
    "NERF_DATASET_LLFF": nerf.DATASET_LLFF,
    "NERF_DATASET_COLMAP": nerf.DATASET_COLMAP,
    "NERF_SCENE_CAPTURE_OBJECT": nerf.SCENE_CAPTURE_OBJECT,
    "NERF_SCENE_CAPTURE_FORWARD": nerf.SCENE_CAPTURE_FORWARD,
    "NERF_SCENE_CAPTURE_UNBOUNDED": nerf.SCENE_CAPTURE_UNBOUNDED,
    "NERF_SCENE_LAYOUT_BLENDER": nerf.SCENE_LAYOUT_BLENDER,
    "NERF_SCENE_LAYOUT_TRANSFORMS": nerf.SCENE_LAYOUT_TRANSFORMS,
    "NERF_SCENE_LAYOUT_LLFF": nerf.SCENE_LAYOUT_LLFF,
    "NERF_SCENE_LAYOUT_COLMAP_TEXT": nerf.SCENE_LAYOUT_COLMAP_TEXT,
    "NERF_SCENE_LAYOUT_COLMAP_BINARY": nerf.SCENE_LAYOUT_COLMAP_BINARY,
    "NERF_IMAGE_MAX_SIDE": nerf.IMAGE_MAX_SIDE,
    "NERF_CAMERA_PATH_FILE_SIZE": nerf.CAMERA_PATH_FILE_SIZE,
    "NERF_CAMERA_PATH_FILE_INTRINSICS": nerf.CAMERA_PATH_FILE_INTRINSICS,
    "NERF_SCENE_LAYOUT_BLENDER": nerf.SCENE_LAYOUT_BLENDER,
    "NERF_SCENE_LAYOUT_TRANSFORMS": nerf.SCENE_LAYOUT_TRANSFORMS,
}


class Layout(TestCase):
    @classmethod
    def setUpClass(cls):
        out = subprocess.run([PROBE], capture_output=True, text=True,
                             timeout=60, check=True)
        cls.c = json.loads(out.stdout)

    def test_every_struct_is_mirrored(self):
        mirrored = {cls._c_name_ for cls in structs.ALL_STRUCTS}
        self.assertEqual(set(self.c["structs"]), mirrored)

    def test_sizes_and_offsets(self):
        for cls in structs.ALL_STRUCTS:
            with self.subTest(struct=cls._c_name_):
                c = self.c["structs"][cls._c_name_]
                self.assertEqual(ctypes.sizeof(cls), c["size"])
                names = [name for name, *_ in cls._fields_]
                self.assertEqual(names, list(c["fields"]),
                                 "field names or order differ")
                for name, (offset, size) in c["fields"].items():
                    field = getattr(cls, name)
                    self.assertEqual(field.offset, offset, name)
                    self.assertEqual(field.size, size, name)

    def test_struct_size_is_filled(self):
        for cls in structs.ALL_STRUCTS:
            with self.subTest(struct=cls._c_name_):
                self.assertEqual(cls().struct_size, ctypes.sizeof(cls))

    def test_constants(self):
        self.assertEqual(set(self.c["constants"]), set(CONSTANTS))
        for name, value in self.c["constants"].items():
            self.assertEqual(CONSTANTS[name], value, name)
        self.assertEqual(self.c["noise_auto"], nerf.NOISE_AUTO)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: test_layout.py LAYOUT_PROBE [unittest args]")
    PROBE = sys.argv.pop(1)
    _support.main()
