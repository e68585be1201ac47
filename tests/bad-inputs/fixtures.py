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
