"""Datasets, the built-in scene, PNG files and image metrics."""

from __future__ import annotations

import ctypes
import weakref
from typing import Any, Callable, List, Optional, Tuple, Union

from . import _buffers, _handle
from ._capi import CameraPathP, DatasetP, lib
from .structs import (Camera, CameraPathOptions, DatasetOptions, SceneOptions,
                      c_uint32, integer)

# nerf_split and nerf_dataset_format
SPLIT_TRAIN = 0
SPLIT_VAL = 1
SPLIT_TEST = 2
SPLITS = {"train": SPLIT_TRAIN, "val": SPLIT_VAL, "test": SPLIT_TEST}
DATASET_BLENDER = 1
DATASET_LLFF = 2
DATASET_COLMAP = 3
FORMATS = {DATASET_BLENDER: "blender", DATASET_LLFF: "llff",
           DATASET_COLMAP: "colmap"}

# nerf_scene_options.capture and .layout, and their names.
SCENE_CAPTURE_OBJECT = 0
SCENE_CAPTURE_FORWARD = 1
SCENE_CAPTURE_UNBOUNDED = 2
SCENE_CAPTURE_WALK = 3
SCENE_CAPTURES = {"object": SCENE_CAPTURE_OBJECT,
                  "forward": SCENE_CAPTURE_FORWARD,
                  "unbounded": SCENE_CAPTURE_UNBOUNDED,
                  "walk": SCENE_CAPTURE_WALK}
SCENE_APPEARANCE_CONSTANT = 0
SCENE_APPEARANCE_VARIED = 1
SCENE_LAYOUT_BLENDER = 0
SCENE_LAYOUT_TRANSFORMS = 1
SCENE_LAYOUT_LLFF = 2
SCENE_LAYOUT_COLMAP_TEXT = 3
SCENE_LAYOUT_COLMAP_BINARY = 4
SCENE_LAYOUTS = {"blender": SCENE_LAYOUT_BLENDER,
                 "transforms": SCENE_LAYOUT_TRANSFORMS,
                 "llff": SCENE_LAYOUT_LLFF,
                 "colmap-text": SCENE_LAYOUT_COLMAP_TEXT,
                 "colmap-binary": SCENE_LAYOUT_COLMAP_BINARY}

#: Largest width or height the image functions accept.
IMAGE_MAX_SIDE = 16384

# Values of SceneOptions.image_format.
IMAGE_FORMAT_PNG = 0
IMAGE_FORMAT_JPEG = 1

# Flags of nerf_camera_path_options.
CAMERA_PATH_FILE_SIZE = 0x1
CAMERA_PATH_FILE_INTRINSICS = 0x2

# The sides and view count write_scene() takes.
SCENE_MIN_SIDE = 8
SCENE_MAX_SIDE = 4096
SCENE_MAX_VIEWS = 10000

LogFn = Optional[Callable[[int, str], Any]]


class _Lease:
    """Keeps a resource's C object alive while borrowed memory is in use."""

    def __init__(self, res: "_handle._Resource") -> None:
        res.acquire()
        weakref.finalize(self, res.release)


def _split_key(split: Union[str, int]) -> int:
    if isinstance(split, str):
        try:
            return SPLITS[split]
        except KeyError:
            raise ValueError("unknown split %r (known: train, val, test)"
                             % (split,)) from None
    return integer(split, "split")


class Dataset(_handle.Handle):
    """One split of a scene on disk (``nerf_dataset``).

    ``Dataset(path, split="train", downscale=1, ...)`` (the same as
    :meth:`load`); the layout (Blender, LLFF or COLMAP) is detected from
    the files.  Keyword options are fields of :class:`nerf.DatasetOptions`:
    ``forward_facing=1`` places a COLMAP model as LLFF places a
    forward-facing capture, for NDC rays (:attr:`space` then says "ndc").
    """

    _kind = "Dataset"

    def __init__(self, path: Any, split: Union[str, int] = "train", *,
                 log: LogFn = None, log_level: Optional[int] = None,
                 **options: Any) -> None:
        opts = DatasetOptions(**options)
        opts.split = _split_key(split)
        hooks = _handle.make_hooks(log, log_level)
        if hooks is not None:
            opts.hooks = ctypes.pointer(hooks[0])
        res = _handle.create("Dataset", DatasetP, lib.nerf_dataset_load,
                             _handle.destroyer("nerf_dataset_destroy"),
                             _handle.fspath(path), ctypes.byref(opts),
                             keep=hooks[1] if hooks else None)
        super().__init__(res)
        self.path = path

    @classmethod
    def load(cls, path: Any, split: Union[str, int] = "train",
             **kwargs: Any) -> "Dataset":
        """Load one split of the scene in folder ``path``
        (``nerf_dataset_load``).  Failures raise NerfIOError or
        NerfFormatError with a message naming the file and the problem."""
        return cls(path, split, **kwargs)

    def __len__(self) -> int:
        with self._using() as ptr:
            return int(lib.nerf_dataset_count(ptr))

    @property
    def format(self) -> str:
        """"blender", "llff" or "colmap"."""
        with self._using() as ptr:
            code = lib.nerf_dataset_get_format(ptr)
        return FORMATS.get(code, str(code))

    @property
    def image_size(self) -> Tuple[int, int]:
        """(width, height) of every image, after downscaling."""
        w, h = ctypes.c_uint32(), ctypes.c_uint32()
        with self._using() as ptr:
            lib.nerf_dataset_image_size(ptr, ctypes.byref(w), ctypes.byref(h))
        return w.value, h.value

    @property
    def bounds(self) -> Tuple[float, float]:
        """(near, far): the range of t to sample (2, 6 for Blender scenes;
        0, 1 in NDC for LLFF ones)."""
        near, far = ctypes.c_float(), ctypes.c_float()
        with self._using() as ptr:
            lib.nerf_dataset_bounds(ptr, ctypes.byref(near),
                                    ctypes.byref(far))
        return near.value, far.value

    @property
    def is_ndc(self) -> bool:
        """True when rays should be warped to NDC (forward-facing scenes)."""
        with self._using() as ptr:
            return bool(lib.nerf_dataset_is_ndc(ptr))

    @property
    def space(self) -> Tuple[str, float]:
        """(space, bound): the scene space a hash-grid model of this
        dataset should use (``"box"``, ``"ndc"`` or ``"unbounded"``) and
        its ``bound`` (``nerf_dataset_space``)."""
        space, bound = ctypes.c_uint32(), ctypes.c_float()
        with self._using() as ptr:
            lib.nerf_dataset_space(ptr, ctypes.byref(space),
                                   ctypes.byref(bound))
        names = {0: "box", 1: "ndc", 2: "unbounded"}
        return names.get(space.value, str(space.value)), bound.value

    def _index(self, index: int) -> int:
        n = len(self)
        i = integer(index, "index", ctypes.c_int64)
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError("image index %d out of range (dataset has %d)"
                             % (index, n))
        return i

    def image(self, index: int) -> Any:
        """Image ``index`` as a read-only height x width x 3 float array
        (RGB in [0, 1]).

        No copy is made: the array views the dataset's own memory and keeps
        the dataset's C object alive while it (or a view of it) exists,
        even after :meth:`close`.  Copy it to modify it.
        """
        i = self._index(index)
        w, h = self.image_size
        pixels = ctypes.POINTER(ctypes.c_float)()
        with self._using() as ptr:
            lib.nerf_dataset_image(ptr, i, ctypes.byref(pixels))
            lease = _Lease(self._res)
        address = ctypes.cast(pixels, ctypes.c_void_p).value
        return _buffers.borrowed_floats(address, (h, w, 3), lease)

    @property
    def has_masks(self) -> bool:
        """True when some image of the split has a mask
        (``nerf_dataset_has_masks``): its masked pixels are left out of
        training and of nerf-eval's scores.  ``ignore_masks=1`` loads
        none."""
        with self._using() as ptr:
            return bool(lib.nerf_dataset_has_masks(ptr))

    def mask(self, index: int) -> Any:
        """The mask of image ``index`` as a read-only height x width uint8
        array, 1 where the pixel counts and 0 where it is left out, or
        None when the dataset has no masks (``nerf_dataset_mask``).  Like
        :meth:`image`, no copy: it keeps the dataset's C object alive."""
        i = self._index(index)
        w, h = self.image_size
        mask = ctypes.POINTER(ctypes.c_uint8)()
        with self._using() as ptr:
            lib.nerf_dataset_mask(ptr, i, ctypes.byref(mask))
            if not mask:
                return None
            lease = _Lease(self._res)
        address = ctypes.cast(mask, ctypes.c_void_p).value
        return _buffers.borrowed_bytes(address, (h, w), lease)

    def camera(self, index: int) -> Camera:
        """The camera of image ``index`` (a new :class:`nerf.Camera`)."""
        cam = Camera()
        with self._using() as ptr:
            lib.nerf_dataset_camera(ptr, self._index(index),
                                    ctypes.byref(cam))
        return cam

    def cameras(self) -> List[Camera]:
        """The cameras of every image."""
        return [self.camera(i) for i in range(len(self))]

    def spiral_camera(self, index: int, n_views: int = 120) -> Camera:
        """Camera ``index`` of ``n_views`` on the reference's spiral render
        path (LLFF scenes only; NerfInvalidArgument otherwise)."""
        cam = Camera()
        with self._using() as ptr:
            lib.nerf_dataset_spiral_camera(
                ptr, integer(index, "spiral_camera: index"),
                integer(n_views, "spiral_camera: n_views"), ctypes.byref(cam))
        return cam


def load_camera_path(path: Any, *, log: LogFn = None,
                     log_level: Optional[int] = None,
                     **options: Any) -> List[Camera]:
    """The cameras of a camera path file (``nerf_camera_path_load``), in
    file order: a .npy of camera-to-world matrices, shape (N, 3, 4),
    (N, 4, 4), (N, 12) or (N, 16), float32 or float64; or a
    transforms-style JSON file (Blender, instant-ngp).

    Keyword options are fields of :class:`nerf.CameraPathOptions`: width
    and height (default: the file's w and h), focal (pixels) or fov_x
    (degrees), and flags (``CAMERA_PATH_FILE_SIZE``,
    ``CAMERA_PATH_FILE_INTRINSICS``: the file's size or intrinsics win
    where it has them).  A .npy file needs width, height and focal or
    fov_x.  Failures raise NerfFormatError, NerfIOError or
    NerfInvalidArgument with a message naming the file and the problem.
    """
    opts = CameraPathOptions(**options)
    hooks = _handle.make_hooks(log, log_level)
    if hooks is not None:
        opts.hooks = ctypes.pointer(hooks[0])
    cp = CameraPathP()
    lib.nerf_camera_path_load(ctypes.byref(cp), _handle.fspath(path),
                              ctypes.byref(opts))
    try:
        cameras = []
        for i in range(lib.nerf_camera_path_count(cp)):
            cam = Camera()
            lib.nerf_camera_path_camera(cp, i, ctypes.byref(cam))
            cameras.append(cam)
        return cameras
    finally:
        lib.nerf_camera_path_destroy(cp)


def write_scene(path: Any, *, log: LogFn = None,
                log_level: Optional[int] = None, **options: Any) -> None:
    """Write the built-in scene to folder ``path`` (``nerf_scene_write``).
    Keyword options are fields of :class:`nerf.SceneOptions` (width,
    height, n_train, n_val, n_test, threads, seed, capture, layout,
    image_format, jpeg_quality, the lens k1, k2, p1, p2, k3, and texture);
    capture and layout may be given by name ("object", "forward",
    "unbounded", "walk"; "blender", "llff", ...).  As in C, the layout defaults to
    Blender whatever the capture: a forward capture is usually written
    with layout="llff"."""
    for key, names in (("capture", SCENE_CAPTURES),
                       ("layout", SCENE_LAYOUTS)):
        value = options.get(key)
        if isinstance(value, str):
            if value not in names:
                raise ValueError("%s must be one of %s, not %r"
                                 % (key, ", ".join(names), value))
            options[key] = names[value]
    opts = SceneOptions(**options)
    hooks = _handle.make_hooks(log, log_level)
    if hooks is not None:
        opts.hooks = ctypes.pointer(hooks[0])
    lib.nerf_scene_write(_handle.fspath(path), ctypes.byref(opts))


class _CBuffer:
    """Memory from the library, released with nerf_free when collected."""

    def __init__(self, address: int) -> None:
        weakref.finalize(self, lib.nerf_free, address)


def read_png(path: Any) -> Any:
    """Read a PNG file as a height x width x 4 float array of straight RGBA
    in [0, 1] (``nerf_image_read_png``).  The array wraps the library's
    buffer without copying and frees it when collected."""
    return _read_rgba(lib.nerf_image_read_png, path)


def read_image(path: Any) -> Any:
    """Read a PNG or JPEG file (told apart by its first bytes; a JPEG is
    turned upright by its Exif orientation) as :func:`read_png` does
    (``nerf_image_read``)."""
    return _read_rgba(lib.nerf_image_read, path)


def _read_rgba(reader: Any, path: Any) -> Any:
    w, h = ctypes.c_uint32(), ctypes.c_uint32()
    pixels = ctypes.POINTER(ctypes.c_float)()
    reader(_handle.fspath(path), ctypes.byref(w), ctypes.byref(h),
           ctypes.byref(pixels))
    address = ctypes.cast(pixels, ctypes.c_void_p).value
    owner = _CBuffer(address)
    return _buffers.borrowed_floats(address, (h.value, w.value, 4), owner,
                                    readonly=False)


def _image_geometry(shape: Tuple[int, ...], width: Optional[int],
                    height: Optional[int], channels: Optional[int],
                    name: str) -> Tuple[int, int, int]:
    """(width, height, channels) of an image argument: from its shape,
    (height, width) or (height, width, channels), which values given
    must agree with; a flat buffer needs width and height."""
    given = [None if v is None else integer(v, k) for v, k in (
        (width, "width"), (height, "height"), (channels, "channels"))]
    width, height, channels = given
    if len(shape) == 1:
        if width is None or height is None:
            raise ValueError("%s: a flat buffer of %d values needs width and "
                             "height" % (name, shape[0]))
        pixels = width * height
        if channels is None:
            if pixels == 0 or shape[0] % pixels:
                raise ValueError("%s: %d values do not fill %d x %d pixels"
                                 % (name, shape[0], width, height))
            channels = shape[0] // pixels
        _buffers.match_shape(shape, (height, width, channels), name)
        return width, height, channels
    if len(shape) not in (2, 3):
        raise ValueError("%s: expected shape (height, width) or (height, "
                         "width, channels), got %s" % (name, shape))
    want = (height, width) + ((channels,) if len(shape) == 3 else ())
    found = _buffers.match_shape(shape, want, name)
    if len(shape) == 2 and channels not in (None, 1):
        raise ValueError("%s: shape %s has 1 channel, not %d"
                         % (name, shape, channels))
    return found[1], found[0], found[2] if len(shape) == 3 else 1


def write_png(path: Any, pixels: Any, width: Optional[int] = None,
              height: Optional[int] = None,
              channels: Optional[int] = None) -> None:
    """Write an 8-bit PNG (gray, RGB or RGBA).

    Float data (``nerf_image_write_png``) is clamped to [0, 1] and rounded;
    uint8 arrays and byte buffers (``bytes``, ``bytearray``, memoryviews of
    format 'B') are written as they are (``nerf_image_write_png8``).  The
    geometry is the array's shape, (height, width) or (height, width,
    channels); width, height and channels, when given, must agree with it.
    A flat buffer needs width and height (and channels, unless its length
    tells them).
    """
    raw = _handle.fspath(path)
    if _buffers.is_uint8(pixels):
        ptr, _, keep, shape = _buffers.as_uint8_input(pixels, "pixels")
        w, h, c = _image_geometry(shape, width, height, channels, "pixels")
        lib.nerf_image_write_png8(raw, w, h, c, ptr)
        del keep
        return
    buf = _buffers.as_float_input(pixels, "pixels")
    w, h, c = _image_geometry(buf.shape, width, height, channels, "pixels")
    lib.nerf_image_write_png(raw, w, h, c, buf.ptr)


def write_npy(path: Any, values: Any, shape: Optional[Any] = None) -> None:
    """Write float data as a float32 NumPy ``.npy`` file with the library's
    own writer (``nerf_npy_write_float``, libnerf 0.5), through a temporary
    file renamed into place.  The shape (1 to 4 dimensions) is the
    array's, unless given; then the array must have that shape (or be
    flat and hold that many values); ``numpy.load`` reads the file back."""
    raw = _handle.fspath(path)
    if shape is not None:
        shape = tuple(integer(d, "shape", ctypes.c_size_t) for d in shape)
    buf = _buffers.as_float_input(values, "values", shape=shape)
    dims = buf.shape
    if not 1 <= len(dims) <= 4:
        raise ValueError("write_npy: values: %d dimensions, the file may "
                         "have 1 to 4" % len(dims))
    c_shape = (ctypes.c_size_t * len(dims))(*dims)
    lib.nerf_npy_write_float(raw, buf.ptr, c_shape, len(dims))


def _mask_input(mask: Any, pixels: int, name: str) -> Any:
    ptr, n, keep, _ = _buffers.as_uint8_input(mask, name)
    if n != pixels:
        raise ValueError("%s: %d values for %d pixels" % (name, n, pixels))
    return ptr, keep


def psnr(a: Any, b: Any, mask: Any = None) -> float:
    """Peak signal-to-noise ratio in dB of two images in [0, 1] of any
    (equal) layout; ``inf`` for identical images (``nerf_psnr``).  With
    ``mask`` (one byte a pixel, 0 = leave out, as :meth:`Dataset.mask`;
    the images then (height, width, channels) or (pixels, channels)),
    over the kept pixels only (``nerf_psnr_masked``)."""
    # The library refuses images that hold NaN or infinite values.
    x = _buffers.as_float_input(a, "psnr: a", finite=True)
    y = _buffers.as_float_input(b, "psnr: b", shape=x.shape, finite=True)
    out = ctypes.c_double()
    if mask is None:
        lib.nerf_psnr(x.ptr, y.ptr, x.size, ctypes.byref(out))
        return out.value
    channels = x.shape[-1] if len(x.shape) >= 2 else 1
    pixels = x.size // channels
    mp, keep = _mask_input(mask, pixels, "psnr: mask")
    lib.nerf_psnr_masked(x.ptr, y.ptr, mp, pixels, channels,
                         ctypes.byref(out))
    del keep
    return out.value


def ssim(a: Any, b: Any, width: Optional[int] = None,
         height: Optional[int] = None,
         channels: Optional[int] = None, mask: Any = None) -> float:
    """Structural similarity of two images in [0, 1] as the reference NeRF
    evaluation computes it (``nerf_ssim``); at least 11 x 11 pixels.  The
    geometry comes from the shape of ``a``, (height, width[, channels]),
    unless given.  With ``mask`` (height x width bytes, 0 = leave out),
    over the windows that hold no left-out pixel
    (``nerf_ssim_masked``)."""
    x = _buffers.as_float_input(a, "ssim: a", finite=True)
    w, h, c = _image_geometry(x.shape, width, height, channels, "ssim: a")
    y = _buffers.as_float_input(b, "ssim: b", shape=x.shape, finite=True)
    out = ctypes.c_double()
    if mask is None:
        lib.nerf_ssim(x.ptr, y.ptr, w, h, c, ctypes.byref(out))
        return out.value
    mp, keep = _mask_input(mask, w * h, "ssim: mask")
    lib.nerf_ssim_masked(x.ptr, y.ptr, mp, w, h, c, ctypes.byref(out))
    del keep
    return out.value
