"""The built-in scene, datasets, PNG files and metrics."""

import array
import json
import math
import os
import shutil
import struct

import _support
from _support import TestCase, flat, nerf, shape


class Scene(TestCase):
    def test_write(self):
        d = _support.scene_dir()
        for name in ("transforms_train.json", "transforms_val.json",
                     "transforms_test.json"):
            self.assertTrue(os.path.isfile(os.path.join(d, name)), name)
        opts = nerf.SceneOptions()
        self.assertEqual(opts.width, 100)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.write_scene(os.path.join(_support.tmpdir(), "bad"), width=0)
        blocker = os.path.join(_support.tmpdir(), "a-file")
        open(blocker, "w").close()
        with self.assertNerfError(nerf.NerfIOError, nerf.EIO, "a-file"):
            nerf.write_scene(os.path.join(blocker, "scene"), width=8,
                             height=8, n_train=1, n_val=1, n_test=1)
        logged = []
        nerf.write_scene(os.path.join(_support.tmpdir(), "logged"), width=8,
                         height=8, n_train=1, n_val=1, n_test=1,
                         log=lambda lvl, msg: logged.append(msg))

    def test_captures(self):
        fwd = os.path.join(_support.tmpdir(), "forward")
        nerf.write_scene(fwd, width=16, height=12, n_train=7, n_test=2,
                         capture="forward", layout="llff")
        with nerf.Dataset.load(fwd, "train") as ds:
            self.assertEqual(ds.format, "llff")
            self.assertTrue(ds.is_ndc)
            self.assertEqual(len(ds), 7)
            self.assertEqual(ds.image_size, (16, 12))
        cm = os.path.join(_support.tmpdir(), "forward-colmap")
        nerf.write_scene(cm, width=16, height=12, n_train=8,
                         capture="forward", layout="colmap-binary")
        with nerf.Dataset.load(cm, "train") as ds:
            self.assertEqual((ds.format, ds.space[0]),
                             ("colmap", "unbounded"))
        with nerf.Dataset.load(cm, "train", forward_facing=1) as ds:
            self.assertEqual((ds.format, ds.space[0], ds.is_ndc),
                             ("colmap", "ndc", True))
        out = os.path.join(_support.tmpdir(), "unbounded")
        nerf.write_scene(out, width=16, height=12, n_train=2, n_val=1,
                         n_test=1, capture=nerf.SCENE_CAPTURE_UNBOUNDED)
        with nerf.Dataset.load(out, "train") as ds:
            self.assertEqual(ds.format, "blender")
            self.assertFalse(ds.is_ndc)
        # The walk, textured (0.13): its train views load in path order,
        # and a texture other than 0 or 1 is refused by the library.
        walk = os.path.join(_support.tmpdir(), "walk")
        nerf.write_scene(walk, width=16, height=12, n_train=3, n_val=0,
                         n_test=0, capture="walk", texture=1)
        with nerf.Dataset.load(walk, "train") as ds:
            self.assertEqual((ds.format, len(ds)), ("blender", 3))
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "texture 2 is not 0 or 1"):
            nerf.write_scene(walk, capture=nerf.SCENE_CAPTURE_WALK,
                             texture=2)
        with self.assertRaises(ValueError):
            nerf.write_scene(out, capture="sideways")
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "forward-facing captures only"):
            nerf.write_scene(out, layout="llff")


class Datasets(TestCase):
    def test_train_split(self):
        with nerf.Dataset.load(_support.scene_dir(), "train") as ds:
            self.assertEqual(len(ds), 3)
            self.assertEqual(ds.format, "blender")
            self.assertEqual(ds.image_size, (16, 16))
            self.assertEqual(ds.bounds, (2.0, 6.0))
            self.assertFalse(ds.is_ndc)
            img = ds.image(0)
            self.assertEqual(shape(img), (16, 16, 3))
            self.assertTrue(all(0.0 <= v <= 1.0 for v in flat(img)))
            self.assertEqual(flat(ds.image(-1)), flat(ds.image(2)))
            with self.assertRaises(IndexError):
                ds.image(3)
            cam = ds.camera(1)
            self.assertEqual((cam.width, cam.height), (16, 16))
            self.assertGreater(cam.fx, 0)
            cams = ds.cameras()
            self.assertEqual(len(cams), 3)
            self.assertEqual(cams[1].pose, cam.pose)
            # The eye lies on the sphere of radius 4 around the scene.
            eye = [row[3] for row in cam.pose]
            self.assertAlmostEqual(math.sqrt(sum(v * v for v in eye)), 4.0,
                                   places=4)
            with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
                ds.spiral_camera(0, 10)   # Blender scenes have no spiral

    def test_image_is_a_readonly_view(self):
        ds = nerf.Dataset(_support.scene_dir())
        img = ds.image(0)
        with self.assertRaises((ValueError, TypeError)):
            img[0, 0, 0] = 0.5
        values = flat(img)
        ds.close()
        # The view keeps the dataset's memory alive after close().
        self.assertEqual(flat(img), values)
        with self.assertRaises(ValueError):
            len(ds)

    def test_options_and_splits(self):
        with nerf.Dataset(_support.scene_dir(), nerf.SPLIT_TEST) as test:
            self.assertEqual(len(test), 2)
        with nerf.Dataset(_support.scene_dir(), "val", downscale=2,
                          white_background=0) as val:
            self.assertEqual(len(val), 1)
            self.assertEqual(val.image_size, (8, 8))
        with nerf.Dataset(_support.scene_dir(), "train", skip=2) as ds:
            self.assertEqual(len(ds), 2)
        with self.assertRaises(ValueError):
            nerf.Dataset(_support.scene_dir(), "holdout")

    def test_errors_name_the_file(self):
        missing = os.path.join(_support.tmpdir(), "no-scene")
        with self.assertNerfError(nerf.NerfNotFound, nerf.ENOENT, "no-scene"):
            nerf.Dataset(missing)
        broken = os.path.join(_support.tmpdir(), "broken")
        shutil.copytree(_support.scene_dir(), broken)
        path = os.path.join(broken, "transforms_train.json")
        with open(path, "w") as f:
            f.write("{ not json")
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT,
                                  "transforms_train.json"):
            nerf.Dataset(broken)
        with open(path, "w") as f:
            json.dump({"camera_angle_x": 0.7}, f)
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT,
                                  "frames"):
            nerf.Dataset(broken)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.Dataset(_support.scene_dir(), downscale=0)


def write_npy(path, descr, shape, values):
    """A .npy file written by hand, so that no NumPy is needed."""
    header = "{'descr': '%s', 'fortran_order': False, 'shape': %r, }" % (
        descr, tuple(shape))
    header += " " * (63 - (10 + len(header)) % 64) + "\n"
    fmt = "<%d%s" % (len(values), "f" if descr == "<f4" else "d")
    with open(path, "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)))
        f.write(header.encode("ascii") + struct.pack(fmt, *values))


# Two camera-to-world matrices, 4 x 4, row by row.
POSES = [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 4, 0, 0, 0, 1],
         [0, 0, 1, 4, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 0, 1]]


class Masks(TestCase):
    def test_occluded_scene_has_masks(self):
        out = os.path.join(_support.tmpdir(), "occluded")
        nerf.write_scene(out, width=16, height=16, n_train=4, n_val=0,
                         n_test=2, occluders=1)
        with nerf.Dataset(out) as ds:
            self.assertTrue(ds.has_masks)
            w, h = ds.image_size
            painted, clear = bytes(ds.mask(0)), bytes(ds.mask(1))
            self.assertEqual(len(painted), w * h)
            self.assertEqual(set(clear), {1})
            self.assertEqual(set(painted), {0, 1})
            self.assertEqual(shape(ds.mask(-4)), (h, w))
            with self.assertRaises(IndexError):
                ds.mask(4)
            a, b = ds.image(0), ds.image(1)
            # Over every pixel, as without a mask; the masked pixels
            # changing leaves the masked score as it was.
            self.assertEqual(nerf.psnr(a, b, mask=clear), nerf.psnr(a, b))
            self.assertEqual(nerf.ssim(a, b, mask=clear), nerf.ssim(a, b))
            kept = nerf.psnr(a, b, mask=painted)
            self.assertNotEqual(kept, nerf.psnr(a, b))
            with self.assertRaises(ValueError):
                nerf.psnr(a, b, mask=painted[:10])
        with nerf.Dataset(out, ignore_masks=1) as ds:
            self.assertFalse(ds.has_masks)
            self.assertIsNone(ds.mask(0))
        with nerf.Dataset(out, "test") as ds:
            self.assertFalse(ds.has_masks)

    def test_llff_masks_folder(self):
        """COLMAP's convention, masks/<image name>.png, in an LLFF scene;
        every photo needs its mask once the folder is there."""
        out = os.path.join(_support.tmpdir(), "llff-masked")
        nerf.write_scene(out, capture="forward", layout="llff", width=16,
                         height=12, n_train=7, n_test=2)
        names = sorted(os.listdir(os.path.join(out, "images")))
        os.mkdir(os.path.join(out, "masks"))
        for k, name in enumerate(names):
            # Photo k leaves its first k pixels out.
            pixels = bytes([0] * k + [255] * (16 * 12 - k))
            nerf.write_png(os.path.join(out, "masks", name + ".png"), pixels,
                           16, 12, 1)
        with nerf.Dataset(out) as ds:
            self.assertTrue(ds.has_masks)
            # The train split: photos 1..7 (photo 0 and 8 held out).
            for i in range(len(ds)):
                m = bytes(ds.mask(i))
                self.assertEqual(m.count(0), i + 1)
                self.assertEqual(m[:i + 1], bytes(i + 1))
        with nerf.Dataset(out, downscale=2) as ds:
            # A 2x2 block is kept only when all its pixels are.
            self.assertEqual(bytes(ds.mask(0))[:2], bytes([0, 1]))
        os.remove(os.path.join(out, "masks", names[8] + ".png"))
        with self.assertRaises(nerf.NerfNotFound) as cm:
            nerf.Dataset(out)
        self.assertIn(names[8] + ".png", str(cm.exception))

    def test_mask_of_another_size_names_it(self):
        out = os.path.join(_support.tmpdir(), "occluded-bad")
        nerf.write_scene(out, width=16, height=16, n_train=4, n_val=0,
                         n_test=2, occluders=1)
        nerf.write_png(os.path.join(out, "train", "masks", "r_2.png"),
                       bytes([255] * 64), 8, 8, 1)
        with self.assertRaises(nerf.NerfFormatError) as cm:
            nerf.Dataset(out)
        self.assertIn("r_2.png: mask is 8x8 but its photo", str(cm.exception))


class CameraPaths(TestCase):
    def test_npy(self):
        path = os.path.join(_support.tmpdir(), "path.npy")
        write_npy(path, "<f8", (2, 4, 4), POSES[0] + POSES[1])
        cams = nerf.load_camera_path(path, width=32, height=24, fov_x=90)
        self.assertEqual(len(cams), 2)
        for cam, pose in zip(cams, POSES):
            self.assertIsInstance(cam, nerf.Camera)
            self.assertEqual(list(cam.c2w), [float(v) for v in pose[:12]])
            self.assertEqual((cam.width, cam.height), (32, 24))
            self.assertAlmostEqual(cam.fx, 16.0, places=4)
            self.assertEqual((cam.cx, cam.cy), (16.0, 12.0))
        # 3 x 4 float32, flattened: the same cameras.
        flat12 = os.path.join(_support.tmpdir(), "path12.npy")
        write_npy(flat12, "<f4", (2, 12), POSES[0][:12] + POSES[1][:12])
        again = nerf.load_camera_path(flat12, width=32, height=24, focal=16)
        self.assertEqual([c.pose for c in again], [c.pose for c in cams])
        # The camera works with the rest of the API.
        origins, _ = cams[1].rays(0, 1)
        self.assertEqual(flat(origins), [4.0, 0.0, 0.0])

    def test_numpy_save(self):
        try:
            import numpy as np
        except ImportError:
            self.skipTest("NumPy is not installed")
        path = os.path.join(_support.tmpdir(), "saved.npy")
        np.save(path, np.array(POSES, dtype=np.float32).reshape(2, 4, 4))
        cams = nerf.load_camera_path(path, width=8, height=8, fov_x=60)
        self.assertEqual(cams[1].pose[2], [-1.0, 0.0, 0.0, 0.0])

    def test_json(self):
        path = os.path.join(_support.scene_dir(), "transforms_test.json")
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "transforms_test.json",
                                  "set width and height"):
            nerf.load_camera_path(path)
        logged = []
        cams = nerf.load_camera_path(
            path, width=20, height=10, log=lambda lvl, msg: logged.append(msg))
        with nerf.Dataset(_support.scene_dir(), "test") as ds:
            self.assertEqual(len(cams), len(ds))
            ref = ds.camera(0)
        self.assertEqual((cams[0].width, cams[0].height), (20, 10))
        self.assertEqual(cams[0].pose, ref.pose)
        self.assertAlmostEqual(cams[0].fx, ref.fx * 20 / ref.width, places=3)
        self.assertTrue(any("camera path of" in m for m in logged))
        # fov_x replaces the file's angle unless the file comes first.
        wide = nerf.load_camera_path(path, width=20, height=10, fov_x=90)
        self.assertAlmostEqual(wide[0].fx, 10.0, places=4)
        kept = nerf.load_camera_path(
            path, width=20, height=10, fov_x=90,
            flags=nerf.CAMERA_PATH_FILE_INTRINSICS)
        self.assertAlmostEqual(kept[0].fx, cams[0].fx, places=4)

    def test_errors(self):
        d = _support.tmpdir()
        npy = os.path.join(d, "bad.npy")
        write_npy(npy, "<f4", (2, 3, 3), [1.0] * 18)
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT,
                                  "bad.npy", "shape is (2, 3, 3)"):
            nerf.load_camera_path(npy, width=8, height=8, fov_x=50)
        good = os.path.join(d, "good.npy")
        write_npy(good, "<f8", (1, 4, 4), POSES[0])
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "good.npy", "set focal or fov_x"):
            nerf.load_camera_path(good, width=8, height=8)
        nan = os.path.join(d, "nan.npy")
        write_npy(nan, "<f8", (1, 4, 4), [float("nan")] + POSES[0][1:])
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT,
                                  "nan.npy", "NaN"):
            nerf.load_camera_path(nan, width=8, height=8, fov_x=50)
        with self.assertNerfError(nerf.NerfNotFound, nerf.ENOENT, "absent.json"):
            nerf.load_camera_path(os.path.join(d, "absent.json"))
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL,
                                  "not both"):
            nerf.load_camera_path(good, width=8, height=8, focal=5,
                                  fov_x=50)
        with self.assertRaises(TypeError):
            nerf.load_camera_path(good, hooks=None)


class Png(TestCase):
    def test_float_round_trip(self):
        path = os.path.join(_support.tmpdir(), "f.png")
        pixels = [[[x / 3, y / 2, 0.5] for x in range(4)] for y in range(3)]
        nerf.write_png(path, pixels)
        back = nerf.read_png(path)
        self.assertEqual(shape(back), (3, 4, 4))
        rgba = flat(back)
        want = flat(pixels)
        self.assertAllClose(rgba[0:3], want[0:3], 0.003)
        self.assertAllClose(rgba[-4:-1], want[-3:], 0.003)
        self.assertEqual(rgba[3], 1.0)

    def test_uint8_and_gray(self):
        path = os.path.join(_support.tmpdir(), "u8.png")
        data = bytes(range(0, 256, 16)) * 3   # 4 x 4 RGB
        nerf.write_png(path, data, width=4, height=4)
        back = nerf.read_png(path)
        self.assertAllClose(flat(back)[0:3], [0, 16 / 255, 32 / 255], 1e-6)
        gray = os.path.join(_support.tmpdir(), "gray.png")
        nerf.write_png(gray, array.array("f", [0.25] * 6), width=3, height=2)
        g = flat(nerf.read_png(gray))
        self.assertAllClose(g[0:4], [64 / 255] * 3 + [1.0], 1e-6)
        with self.assertRaises(ValueError):
            nerf.write_png(gray, array.array("f", [0.25] * 6))
        with self.assertRaises(ValueError):
            nerf.write_png(gray, array.array("f", [0.25] * 7), 3, 2)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.write_png(gray, array.array("f", [0.25] * 12), 3, 2, 2)

    def test_errors(self):
        missing = os.path.join(_support.tmpdir(), "missing.png")
        with self.assertNerfError(nerf.NerfNotFound, nerf.ENOENT, missing):
            nerf.read_png(missing)
        junk = os.path.join(_support.tmpdir(), "junk.png")
        with open(junk, "wb") as f:
            f.write(b"\x89PNG but not really")
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT, junk):
            nerf.read_png(junk)
        bad_dir = os.path.join(_support.tmpdir(), "nowhere", "x.png")
        with self.assertNerfError(nerf.NerfIOError, nerf.EIO, "nowhere"):
            nerf.write_png(bad_dir, bytes(3), 1, 1)

    def test_read_image_jpeg_scene(self):
        out = os.path.join(_support.tmpdir(), "jpeg_scene")
        nerf.write_scene(out, width=16, height=8, n_train=1, n_val=0,
                         n_test=0, image_format=nerf.IMAGE_FORMAT_JPEG,
                         jpeg_quality=90)
        img = nerf.read_image(os.path.join(out, "train", "r_0.jpg"))
        self.assertEqual(shape(img), (8, 16, 4))
        self.assertEqual(flat(img)[3], 1.0)
        png = os.path.join(_support.tmpdir(), "f.png")
        nerf.write_png(png, bytes(range(12)), width=2, height=2)
        self.assertEqual(shape(nerf.read_image(png)), (2, 2, 4))
        junk = os.path.join(_support.tmpdir(), "junk.jpg")
        with open(junk, "wb") as f:
            f.write(b"GIF89a")
        with self.assertNerfError(nerf.NerfFormatError, nerf.EFORMAT,
                                  "not a PNG or JPEG file"):
            nerf.read_image(junk)

    def test_scene_image_matches_dataset(self):
        png = nerf.read_png(os.path.join(_support.scene_dir(), "train",
                                         "r_0.png"))
        self.assertEqual(shape(png), (16, 16, 4))


class Metrics(TestCase):
    def test_psnr(self):
        a = [0.5] * 12
        self.assertEqual(nerf.psnr(a, a), math.inf)
        b = [0.6] * 12
        self.assertAlmostEqual(nerf.psnr(a, b), 20.0, places=4)
        with self.assertRaises(ValueError):
            nerf.psnr(a, b[:6])
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.psnr([math.nan] * 3, [0.0] * 3)

    def test_ssim(self):
        with nerf.Dataset(_support.scene_dir()) as ds:
            a, b = ds.image(0), ds.image(1)
            self.assertAlmostEqual(nerf.ssim(a, a), 1.0, places=6)
            s = nerf.ssim(a, b)
            self.assertLess(s, 1.0)
            self.assertAlmostEqual(nerf.ssim(flat(a), flat(b), 16, 16, 3), s,
                                   places=9)
        with self.assertNerfError(nerf.NerfInvalidArgument, nerf.EINVAL):
            nerf.ssim([0.0] * 100, [0.0] * 100, 10, 10, 1)


if __name__ == "__main__":
    _support.main()
