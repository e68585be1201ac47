"""The inputs the cases of cases.txt name as {NAME}: each built once, on
first use, by the function registered under NAME.  A builder returns the
path it made; it may use other fixtures through fx.get() and run the
programs through fx.tool()."""

import json
import os
import shutil
import socket
import struct
import zlib

BUILDERS = {}


class FixtureError(Exception):
    """A fixture could not be built: the case cannot run."""


def fixture(name):
    def register(build):
        if name in BUILDERS:
            raise RuntimeError("fixture %s defined twice" % name)
        BUILDERS[name] = build
        return build
    return register


class Fixtures:
    def __init__(self, runner, root):
        self.runner = runner
        self.root = root
        self.made = {}
        os.makedirs(root)

    def get(self, name):
        if name not in self.made:
            if name not in BUILDERS:
                raise FixtureError("no fixture named {%s}" % name)
            self.made[name] = BUILDERS[name](self, self.path(name))
        return self.made[name]

    def path(self, name):
        """Where the fixture called name goes (nothing is there yet)."""
        return os.path.join(self.root, name)

    def tool(self, program, *args):
        """Run one of the programs to make a fixture; it must succeed."""
        status, _, err = self.runner.run(self.runner.program(program) +
                                         [str(a) for a in args])
        if status != 0:
            raise FixtureError("%s %s: status %s: %s" % (
                program, " ".join(map(str, args)), status,
                err.decode("utf-8", "replace").strip()))

    def copy(self, name, path):
        """A copy of fixture name at path, to be damaged."""
        src = self.get(name)
        if os.path.isdir(src):
            shutil.copytree(src, path, symlinks=True)
        else:
            shutil.copyfile(src, path)
        return path


def write(path, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path, mode) as f:
        f.write(data)
    return path


# ---- plain things ----------------------------------------------------------

@fixture("fifo")
def _fifo(fx, path):
    os.mkfifo(path)
    return path


@fixture("folder")
def _folder(fx, path):
    os.mkdir(path)
    return path


@fixture("empty")
def _empty(fx, path):
    return write(path, b"")


# ---- videos (nerf-frames) -----------------------------------------------------

@fixture("audio")
def _audio(fx, path):
    """A WAV file of a tenth of a second of silence: a file FFmpeg reads,
    with one stream, and that not a video."""
    rate = 8000
    data = b"\0\0" * (rate // 10)
    fmt = struct.pack("<HHIIHH", 1, 1, rate, 2 * rate, 2, 16)
    body = (b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt +
            b"data" + struct.pack("<I", len(data)) + data)
    return write(path + ".wav",
                 b"RIFF" + struct.pack("<I", len(body)) + body)


@fixture("video-no-frames")
def _video_no_frames(fx, path):
    """A YUV4MPEG2 video's header and no frame: a video stream, empty."""
    return write(path + ".y4m", b"YUV4MPEG2 W16 H16 F10:1 Ip A1:1 C420jpeg\n")


@fixture("still-image")
def _still_image(fx, path):
    """One of the built-in scene's photos, as JPEG: a photo, not a
    video."""
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 1, "--val", 0, "--test", 0, "--format", "jpeg")
    return os.path.join(path, "train", "r_0.jpg")


# ---- a scene and a model trained on it --------------------------------------

@fixture("scene")
def _scene(fx, path):
    """The built-in scene in Blender layout, small: 16x16, 4 training and 2
    test views."""
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 4, "--val", 0, "--test", 2)
    return path


@fixture("model")
def _model(fx, path):
    """A checkpoint of two training steps on {scene}."""
    path += ".nerf"
    fx.tool("nerf-train", "--data", fx.get("scene"), "--out", path,
            "--steps", 2, "--batch", 64, "--coarse-samples", 8,
            "--fine-samples", 16)
    return path


# ---- programs: what they write (issue 53, the example programs) ------------

@fixture("model-link")
def _model_link(fx, path):
    """A hard link to {model}: the same file under another name."""
    os.link(fx.get("model"), path)
    return path


@fixture("model-symlink")
def _model_symlink(fx, path):
    """A symbolic link to {model}."""
    os.symlink(fx.get("model"), path)
    return path


@fixture("model-ply")
def _model_ply(fx, path):
    """{model} hard-linked under a name nerf-export mesh would write."""
    path += ".ply"
    os.link(fx.get("model"), path)
    return path


@fixture("taken")
def _taken(fx, path):
    """A file of someone's that a program must not replace unasked."""
    return write(path, "not yours\n")


@fixture("taken-ply")
def _taken_ply(fx, path):
    return write(path + ".ply", "ply\nnot yours\n")


@fixture("grid-taken")
def _grid_taken(fx, path):
    """A folder holding g.json, the sidecar of a grid written as g.npy."""
    os.mkdir(path)
    write(os.path.join(path, "g.json"), "{}\n")
    return path


@fixture("depth-taken")
def _depth_taken(fx, path):
    """A folder holding view 0's distance array, as nerf-export depth
    names it."""
    os.mkdir(path)
    write(os.path.join(path, "000_distance.npy"), b"not yours")
    return path


@fixture("frames-taken")
def _frames_taken(fx, path):
    """A folder holding r_001.png, as nerf-render names view 1."""
    os.mkdir(path)
    write(os.path.join(path, "r_001.png"), b"not yours")
    return path


# ---- readers: files that are not regular, images and datasets ---------------



@fixture("socket")
def _socket(fx, path):
    """A Unix socket's file (left behind: nothing listens on it)."""
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        s.bind(path)
    finally:
        s.close()
    return path


@fixture("device")
def _device(fx, path):
    """/dev/null through a link: a character device."""
    os.symlink("/dev/null", path)
    return path


def png_chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data +
            struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))


def png(width, height, data=None, colour=2):
    """A PNG of width x height 8-bit pixels (colour type 2 RGB, 6 RGBA),
    grey; or with data as its (deflated) image data whatever the size."""
    channels = 4 if colour == 6 else 3
    if data is None:
        row = b"\0" + b"\x80" * (width * channels)
        data = zlib.compress(row * height)
    head = struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", head) +
            png_chunk(b"IDAT", data) + png_chunk(b"IEND", b""))


def jpeg_claiming(jpeg, width, height):
    """The JPEG bytes jpeg with their frame header (SOF0..SOF2) set to
    width x height; the data is left as it was."""
    i = 2
    while i + 4 <= len(jpeg):
        marker, length = jpeg[i + 1], struct.unpack(">H", jpeg[i + 2:i + 4])[0]
        if marker in (0xC0, 0xC1, 0xC2):
            out = bytearray(jpeg)
            out[i + 5:i + 9] = struct.pack(">HH", height, width)
            return bytes(out)
        i += 2 + length
    raise FixtureError("no frame header in the JPEG")


@fixture("png-claims-huge")
def _png_claims_huge(fx, path):
    """A 100-byte PNG whose header claims 16384x16384 RGBA pixels."""
    return write(path + ".png", png(16384, 16384, zlib.compress(b"\0" * 64),
                                    colour=6))


@fixture("scene-jpeg")
def _scene_jpeg(fx, path):
    """{scene}'s layout with JPEG files."""
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 4, "--val", 0, "--test", 2, "--format", "jpeg")
    return path


@fixture("jpeg-claims-huge")
def _jpeg_claims_huge(fx, path):
    """A JPEG of {scene-jpeg} (under 1 KB) whose header claims
    16384x16384 pixels."""
    with open(os.path.join(fx.get("scene-jpeg"), "train", "r_0.jpg"),
              "rb") as f:
        return write(path + ".jpg", jpeg_claiming(f.read(), 16384, 16384))


def damaged(fx, path, base, rel, how):
    """A copy of fixture base with the file rel (under it) replaced:
    how is "fifo", "folder", "device", "missing" or bytes to write."""
    fx.copy(base, path)
    target = os.path.join(path, rel)
    if os.path.lexists(target):
        if os.path.isdir(target) and not os.path.islink(target):
            shutil.rmtree(target)
        else:
            os.remove(target)
    if how == "fifo":
        os.mkfifo(target)
    elif how == "folder":
        os.mkdir(target)
    elif how == "device":
        os.symlink("/dev/null", target)
    elif how != "missing":
        write(target, how)
    return path


def edited(fx, path, base, rel, old, new):
    """A copy of fixture base whose text file rel has old replaced by
    new (which must be there)."""
    fx.copy(base, path)
    target = os.path.join(path, rel)
    with open(target, encoding="utf-8") as f:
        text = f.read()
    if old not in text:
        raise FixtureError("%s: no %r to replace" % (rel, old))
    write(target, text.replace(old, new, 1))
    return path


def register_damage(name, base, rel, how):
    fixture(name)(lambda fx, path: damaged(fx, path, base, rel, how))


# Blender layout ({scene}: 4 train views, 2 test views, 16x16 RGBA PNGs).
register_damage("blender-json-fifo", "scene", "transforms_train.json", "fifo")
register_damage("blender-train-fifo", "scene", "train/r_1.png", "fifo")
register_damage("blender-train-device", "scene", "train/r_1.png", "device")
register_damage("blender-train-folder", "scene", "train/r_1.png", "folder")
register_damage("blender-train-claims-huge", "scene", "train/r_1.png",
                png(16384, 16384, zlib.compress(b"\0" * 64), colour=6))
register_damage("blender-test-fifo", "scene", "test/r_1.png", "fifo")
register_damage("blender-test-missing", "scene", "test/r_1.png", "missing")
register_damage("blender-test-folder", "scene", "test/r_1.png", "folder")
register_damage("blender-test-not-image", "scene", "test/r_1.png",
                b"not an image\n")
register_damage("blender-test-truncated", "scene", "test/r_1.png",
                png(16, 16, colour=6)[:20])
register_damage("blender-test-wrong-size", "scene", "test/r_1.png",
                png(8, 8, colour=6))
register_damage("blender-test-claims-huge", "scene", "test/r_1.png",
                png(16384, 16384, zlib.compress(b"\0" * 64), colour=6))


@fixture("blender-test-dot")
def _blender_test_dot(fx, path):
    """The second test frame's file_path is "."."""
    return edited(fx, path, "scene", "transforms_test.json",
                  '"./test/r_1"', '"."')


@fixture("blender-test-json-broken")
def _blender_test_json_broken(fx, path):
    return edited(fx, path, "scene", "transforms_test.json",
                  '"frames"', '"frames" ]')


# instant-ngp layout: one transforms.json, every 8th frame held out.
@fixture("ngp")
def _ngp(fx, path):
    """The built-in scene as one transforms.json: 9 views of 16x16 in
    images/, view 0 and view 8 held out for test."""
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 7, "--val", 0, "--test", 2, "--layout", "transforms")
    return path


def ngp_image(fx, index):
    """The name under {ngp}/ of view index's image."""
    with open(os.path.join(fx.get("ngp"), "transforms.json"),
              encoding="utf-8") as f:
        text = f.read()
    return json.loads(text)["frames"][index]["file_path"]


@fixture("ngp-held-fifo")
def _ngp_held_fifo(fx, path):
    return damaged(fx, path, "ngp", ngp_image(fx, 8), "fifo")


@fixture("ngp-held-missing")
def _ngp_held_missing(fx, path):
    return damaged(fx, path, "ngp", ngp_image(fx, 8), "missing")


@fixture("ngp-lens")
def _ngp_lens(fx, path):
    """k1 5000: beyond the +-1000 every camera call allows."""
    fx.copy("ngp", path)
    target = os.path.join(path, "transforms.json")
    with open(target, encoding="utf-8") as f:
        data = json.load(f)
    data["k1"] = 5000.0
    write(target, json.dumps(data, indent=1))
    return path


# Masks: {scene-masked} is {scene} with occluders (train views 0 and 2
# masked through mask_path); {colmap-masked} a COLMAP model with masks/.
@fixture("scene-masked")
def _scene_masked(fx, path):
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 4, "--val", 0, "--test", 2, "--occluders")
    return path


register_damage("mask-missing", "scene-masked", "train/masks/r_2.png",
                "missing")
register_damage("mask-fifo", "scene-masked", "train/masks/r_2.png", "fifo")
register_damage("mask-not-image", "scene-masked", "train/masks/r_2.png",
                b"not an image\n")
register_damage("mask-truncated", "scene-masked", "train/masks/r_2.png",
                png(16, 16, colour=0)[:30])
register_damage("mask-wrong-size", "scene-masked", "train/masks/r_2.png",
                png(8, 8))


def _edit_frame(fx, path, base, name, index, key, value):
    if base is not None:
        fx.copy(base, path)
    target = os.path.join(path, name)
    with open(target, encoding="utf-8") as f:
        data = json.load(f)
    data["frames"][index][key] = value
    write(target, json.dumps(data, indent=1))
    return path


@fixture("mask-path-number")
def _mask_path_number(fx, path):
    return _edit_frame(fx, path, "scene-masked", "transforms_train.json", 0,
                       "mask_path", 5)


@fixture("mask-held-wrong-size")
def _mask_held_wrong_size(fx, path):
    """A test frame's mask of another size: refused when the train split
    is loaded, as the test frames' images are checked."""
    fx.copy("scene-masked", path)
    write(os.path.join(path, "test", "m1.png"), png(8, 8))
    return _edit_frame(fx, path, None, "transforms_test.json", 1,
                       "mask_path", "test/m1.png")


@fixture("ngp-dynamic-wrong-size")
def _ngp_dynamic_wrong_size(fx, path):
    """instant-ngp's dynamic mask of view 1 is 8x8."""
    fx.copy("ngp", path)
    image = ngp_image(fx, 1)
    stem = os.path.splitext(os.path.basename(image))[0]
    write(os.path.join(path, os.path.dirname(image),
                       "dynamic_mask_" + stem + ".png"), png(8, 8))
    return path


@fixture("ngp-dynamic-all")
def _ngp_dynamic_all(fx, path):
    """Every view's dynamic mask nonzero everywhere: nothing to train on."""
    fx.copy("ngp", path)
    for i in range(9):
        image = ngp_image(fx, i)
        stem = os.path.splitext(os.path.basename(image))[0]
        write(os.path.join(path, os.path.dirname(image),
                           "dynamic_mask_" + stem + ".png"), png(16, 16))
    return path


@fixture("colmap-masked")
def _colmap_masked(fx, path):
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 4, "--val", 0, "--test", 2, "--layout", "colmap-text",
            "--occluders")
    return path


register_damage("colmap-mask-missing", "colmap-masked",
                "masks/00003.png.png", "missing")
register_damage("colmap-mask-held-wrong-size", "colmap-masked",
                "masks/00000.png.png", png(8, 8))


# LLFF layout: 10 photos of 16x12 in images/, photos 0 and 8 held out.
@fixture("llff")
def _llff(fx, path):
    fx.tool("nerf-scene", "--out", path, "--capture", "forward", "--width",
            16, "--height", 12, "--train", 8, "--test", 2)
    return path


register_damage("llff-npy-fifo", "llff", "poses_bounds.npy", "fifo")
register_damage("llff-train-fifo", "llff", "images/image00001.png", "fifo")
register_damage("llff-held-fifo", "llff", "images/image00008.png", "fifo")
register_damage("llff-held-not-image", "llff", "images/image00008.png",
                b"not an image\n")
register_damage("llff-held-wrong-size", "llff", "images/image00008.png",
                png(8, 6))


@fixture("llff-images2-full-size")
def _llff_images2_full_size(fx, path):
    """images_2/ holding the full-size photos of images/."""
    fx.copy("llff", path)
    shutil.copytree(os.path.join(path, "images"),
                    os.path.join(path, "images_2"))
    return path


# COLMAP layouts: 6 photos of 16x16 in images/, photo 0 held out.
@fixture("colmap-text")
def _colmap_text(fx, path):
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 4, "--val", 0, "--test", 2, "--layout", "colmap-text")
    return path


@fixture("colmap-bin")
def _colmap_bin(fx, path):
    fx.tool("nerf-scene", "--out", path, "--width", 16, "--height", 16,
            "--train", 4, "--val", 0, "--test", 2, "--layout",
            "colmap-binary")
    return path


register_damage("colmap-cameras-fifo", "colmap-bin", "sparse/0/cameras.bin",
                "fifo")
register_damage("colmap-images-fifo", "colmap-text", "sparse/0/images.txt",
                "fifo")
register_damage("colmap-points-fifo", "colmap-bin", "sparse/0/points3D.bin",
                "fifo")
register_damage("colmap-photo-fifo", "colmap-text", "images/00001.png",
                "fifo")
register_damage("colmap-photo-folder", "colmap-text", "images/00001.png",
                "folder")
register_damage("colmap-held-missing", "colmap-text", "images/00000.png",
                "missing")
register_damage("colmap-held-not-image", "colmap-bin", "images/00000.png",
                b"not an image\n")


@fixture("colmap-held-dot")
def _colmap_held_dot(fx, path):
    """Image 1 (00000.png, held out) renamed "."."""
    return edited(fx, path, "colmap-text", "sparse/0/images.txt",
                  " 00000.png\n", " .\n")


@fixture("colmap-lens-text")
def _colmap_lens_text(fx, path):
    """Camera 1 an OPENCV camera with k1 5000."""
    fx.copy("colmap-text", path)
    target = os.path.join(path, "sparse", "0", "cameras.txt")
    with open(target, encoding="utf-8") as f:
        lines = f.read().splitlines()
    out = []
    for line in lines:
        cells = line.split()
        if cells and cells[0] == "1" and cells[1] == "PINHOLE":
            line = " ".join(["1", "OPENCV"] + cells[2:] + ["5000", "0", "0",
                                                           "0"])
        out.append(line)
    write(target, "\n".join(out) + "\n")
    return path


def colmap_cameras_bin(cameras):
    """cameras.bin of (id, model id, width, height, params) records."""
    out = struct.pack("<Q", len(cameras))
    for cam_id, model, width, height, params in cameras:
        out += struct.pack("<IiQQ", cam_id, model, width, height)
        out += struct.pack("<%dd" % len(params), *params)
    return out


def colmap_bin_camera(fx):
    """The one camera of {colmap-bin}: id, width, height, PINHOLE's four
    parameters."""
    with open(os.path.join(fx.get("colmap-bin"), "sparse", "0",
                           "cameras.bin"), "rb") as f:
        data = f.read()
    cam_id, model, width, height = struct.unpack("<IiQQ", data[8:32])
    if model != 1:
        raise FixtureError("cameras.bin: expected one PINHOLE camera")
    return cam_id, width, height, struct.unpack("<4d", data[32:64])


@fixture("colmap-lens-bin")
def _colmap_lens_bin(fx, path):
    cam_id, width, height, p = colmap_bin_camera(fx)
    return damaged(fx, path, "colmap-bin", "sparse/0/cameras.bin",
                   colmap_cameras_bin([(cam_id, 4, width, height,
                                        list(p) + [0.0, -2000.0, 0, 0])]))


@fixture("colmap-cameras-truncated")
def _colmap_cameras_truncated(fx, path):
    """cameras.bin of camera 7 then camera 9, cut inside camera 9's
    parameters."""
    cam_id, width, height, p = colmap_bin_camera(fx)
    data = colmap_cameras_bin([(7, 1, width, height, p),
                               (9, 1, width, height, p)])
    return damaged(fx, path, "colmap-bin", "sparse/0/cameras.bin",
                   data[:-8])


@fixture("colmap-images2-full-size")
def _colmap_images2_full_size(fx, path):
    fx.copy("colmap-text", path)
    shutil.copytree(os.path.join(path, "images"),
                    os.path.join(path, "images_2"))
    return path
# ---- weights: a run that diverged -----------------------------------------

PARAMETERS_TAG = 0x80000003


def forge_weight(src, dst, index, value):
    """Copy the checkpoint src to dst with parameter `index` set to value,
    through the layout docs/formats.md gives: a 48-byte header (magic,
    version, header size, payload sizes, CRCs of both payloads, flags, the
    header's own CRC), then one zlib stream of tagged sections; the
    parameters are the section 0x80000003, n float32."""
    import struct
    import zlib
    with open(src, "rb") as f:
        data = f.read()
    header_size = struct.unpack_from("<I", data, 12)[0]
    payload = bytearray(zlib.decompress(data[header_size:]))
    at = 0
    while at < len(payload):
        tag, length = struct.unpack_from("<IQ", payload, at)
        if tag == PARAMETERS_TAG:
            if 4 * (index + 1) > length:
                raise FixtureError("%s has no parameter %d" % (src, index))
            struct.pack_into("<f", payload, at + 12 + 4 * index, value)
            break
        at += 12 + length
    else:
        raise FixtureError("%s: no parameters section" % src)
    packed = zlib.compress(bytes(payload))
    header = bytearray(data[:header_size])
    struct.pack_into("<QQII", header, 16, len(payload), len(packed),
                     zlib.crc32(packed), zlib.crc32(payload))
    struct.pack_into("<I", header, 44, zlib.crc32(bytes(header[:44])))
    return write(dst, bytes(header) + packed)


@fixture("nan-model")
def _nan_model(fx, path):
    """{model} with one weight NaN, as a run that diverged leaves it: the
    coarse network's trunk layer 0, row 0, column 5 (parameter 5; the tiny
    preset's frequency encoding has no parameters before it)."""
    return forge_weight(fx.get("model"), path + ".nerf", 5, float("nan"))
