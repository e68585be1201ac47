#!/usr/bin/python3
"""Write an LLFF poses_bounds.npy from a COLMAP sparse model.

    /usr/bin/python3 scripts/colmap-to-llff.py MODEL_DIR OUT.npy

MODEL_DIR holds COLMAP's binary cameras.bin, images.bin and points3D.bin
(e.g. OUT/sparse/0 of scripts/colmap-train.sh).  A forward-facing capture
reconstructed by COLMAP then loads as an LLFF scene (NDC rays, the spiral
path) when the .npy sits beside the folder of its photos, which must be
the model's images sorted by name.  The rows follow LLFF's own
conversion (imgs2poses): camera-to-world 3x4 with its columns reordered
from COLMAP's [right, down, forward] to [down, right, back], then
[height, width, focal] as a fifth column, then the 0.1th and 99.9th
percentiles of the depths of the sparse points each image sees.  The
camera's lens is dropped: LLFF scenes are pinhole, so reconstruct with a
pinhole model (colmap-train.sh --camera-model PINHOLE).
"""
import struct
import sys

import numpy as np

# Parameters per COLMAP camera model id (its cameras.h).
N_PARAMS = {0: 3, 1: 4, 2: 4, 3: 5, 4: 8}


def read_cameras(path):
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack_from("<Q", data, 0)
    at, cams = 8, {}
    for _ in range(n):
        cid, model, width, height = struct.unpack_from("<IiQQ", data, at)
        at += 24
        if model not in N_PARAMS:
            sys.exit("%s: camera %d has model %d, which this script does not "
                     "read" % (path, cid, model))
        params = struct.unpack_from("<%dd" % N_PARAMS[model], data, at)
        at += 8 * N_PARAMS[model]
        cams[cid] = (width, height, params[0])
    return cams


def read_images(path):
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack_from("<Q", data, 0)
    at, images = 8, {}
    for _ in range(n):
        iid, qw, qx, qy, qz, tx, ty, tz, cid = struct.unpack_from(
            "<I7dI", data, at)
        at += 64
        end = data.index(b"\0", at)
        name = data[at:end].decode("utf-8")
        (n2d,) = struct.unpack_from("<Q", data, end + 1)
        at = end + 1 + 8 + 24 * n2d
        images[iid] = (name, np.array([qw, qx, qy, qz]),
                       np.array([tx, ty, tz]), cid)
    return images


def read_points(path):
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack_from("<Q", data, 0)
    at, xyz, seen = 8, [], []
    for _ in range(n):
        x, y, z = struct.unpack_from("<3d", data, at + 8)
        (track,) = struct.unpack_from("<Q", data, at + 43)
        ids = struct.unpack_from("<%dI" % (2 * track), data, at + 51)
        at += 51 + 8 * track
        xyz.append((x, y, z))
        seen.append(set(ids[0::2]))
    return np.array(xyz), seen


def rotation(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    model, out = sys.argv[1], sys.argv[2]
    cams = read_cameras(model + "/cameras.bin")
    images = read_images(model + "/images.bin")
    pts, seen = read_points(model + "/points3D.bin")
    rows = []
    for iid in sorted(images, key=lambda i: images[i][0]):
        name, q, t, cid = images[iid]
        width, height, focal = cams[cid]
        r = rotation(q)
        c2w = np.concatenate([r.T, (-r.T @ t)[:, None]], 1)
        # [right, down, forward] -> [down, right, back], as LLFF does.
        pose = np.stack([c2w[:, 1], c2w[:, 0], -c2w[:, 2], c2w[:, 3],
                         [height, width, focal]], 1)
        mine = np.array([iid in s for s in seen])
        if not mine.any():
            sys.exit("%s: image %s sees no sparse point" % (model, name))
        depth = (pts[mine] - c2w[:, 3]) @ c2w[:, 2]
        near, far = np.percentile(depth, 0.1), np.percentile(depth, 99.9)
        rows.append(np.concatenate([pose.ravel(), [near, far]]))
    np.save(out, np.array(rows, dtype="<f8"))
    print("%s: %d images, bounds %.3g .. %.3g" % (
        out, len(rows), min(r[15] for r in rows), max(r[16] for r in rows)))


if __name__ == "__main__":
    main()
