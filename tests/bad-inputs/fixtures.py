"""The inputs the cases of cases.txt name as {NAME}: each built once, on
first use, by the function registered under NAME.  A builder returns the
path it made; it may use other fixtures through fx.get() and run the
programs through fx.tool()."""

import os
import shutil

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
