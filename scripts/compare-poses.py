#!/usr/bin/python3
"""Compare a COLMAP model's poses with an LLFF scene's poses_bounds.npy.

    /usr/bin/python3 scripts/compare-poses.py MODEL_DIR LLFF_DIR

MODEL_DIR holds COLMAP's images.bin and cameras.bin (e.g. OUT/sparse/0 of
scripts/colmap-train.sh); LLFF_DIR holds poses_bounds.npy, whose rows are
the images sorted by name.  Images are paired by their sorted names (the
COLMAP model must hold as many as the .npy has rows).  The two sets of
camera centres are aligned by the least-squares similarity (Umeyama:
scale, rotation, translation); then for each camera:

  rotation error  the angle of R_llff^T A R_colmap, A the alignment's
                  rotation (degrees);
  position error  |c_llff - (s A c_colmap + t)| over the scene extent, the
                  largest distance between two LLFF camera centres.

Prints the mean and largest of each, and the focal lengths of both.
"""
import struct
import sys

import numpy as np


def read_images_bin(path):
    """{name: (qvec, tvec)} of a COLMAP images.bin."""
    out = {}
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack_from("<Q", data, 0)
    at = 8
    for _ in range(n):
        _, qw, qx, qy, qz, tx, ty, tz, _ = struct.unpack_from(
            "<I7dI", data, at)
        at += 64
        end = data.index(b"\0", at)
        name = data[at:end].decode("utf-8")
        at = end + 1
        (n2d,) = struct.unpack_from("<Q", data, at)
        at += 8 + 24 * n2d
        out[name] = (np.array([qw, qx, qy, qz]), np.array([tx, ty, tz]))
    return out


def read_focal(path):
    """Focal length and width of the first camera of a cameras.bin."""
    with open(path, "rb") as f:
        data = f.read()
    _, model, width, _ = struct.unpack_from("<IiQQ", data, 8)
    (f0,) = struct.unpack_from("<d", data, 8 + 24)
    return f0, width, model


def quat_to_matrix(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def umeyama(src, dst):
    """s, R, t minimising sum |dst - (s R src + t)|^2."""
    mu_s, mu_d = src.mean(0), dst.mean(0)
    xs, xd = src - mu_s, dst - mu_d
    cov = xd.T @ xs / len(src)
    u, d, vt = np.linalg.svd(cov)
    sign = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        sign[2, 2] = -1
    rot = u @ sign @ vt
    var = (xs ** 2).sum() / len(src)
    scale = np.trace(np.diag(d) @ sign) / var
    return scale, rot, mu_d - scale * rot @ mu_s


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    model, llff = sys.argv[1], sys.argv[2]
    images = read_images_bin(model + "/images.bin")
    rows = np.load(llff + "/poses_bounds.npy")
    names = sorted(images)
    if len(names) != len(rows):
        sys.exit(f"compare-poses: the model has {len(names)} images, "
                 f"poses_bounds.npy {len(rows)} rows")
    r_col, c_col, r_llff, c_llff = [], [], [], []
    for name, row in zip(names, rows):
        q, t = images[name]
        r = quat_to_matrix(q)              # world-to-camera, OpenCV axes
        r_col.append(r.T)                  # camera-to-world
        c_col.append(-r.T @ t)
        m = row[:15].reshape(3, 5)
        # LLFF's columns are [down, right, back]; OpenCV's [right, down,
        # forward] = [c1, c0, -c2].
        r_llff.append(np.stack([m[:, 1], m[:, 0], -m[:, 2]], axis=1))
        c_llff.append(m[:, 3])
    c_col, c_llff = np.array(c_col), np.array(c_llff)
    scale, rot, trans = umeyama(c_col, c_llff)
    aligned = scale * c_col @ rot.T + trans
    diff = c_llff[:, None, :] - c_llff[None, :, :]
    extent = np.sqrt((diff ** 2).sum(-1)).max()
    pos_err = np.linalg.norm(aligned - c_llff, axis=1) / extent
    rot_err = []
    for ra, rb in zip(r_col, r_llff):
        m = rb.T @ rot @ ra
        cos = np.clip((np.trace(m) - 1) / 2, -1.0, 1.0)
        rot_err.append(np.degrees(np.arccos(cos)))
    rot_err = np.array(rot_err)
    f_col, w_col, model_id = read_focal(model + "/cameras.bin")
    h, w, f = rows[0, 4], rows[0, 9], rows[0, 14]
    print(f"images: {len(names)}")
    print(f"similarity: scale {scale:.6g}")
    print(f"rotation error (deg): mean {rot_err.mean():.3f}, "
          f"max {rot_err.max():.3f}")
    print(f"position error / extent ({extent:.4g}): mean "
          f"{pos_err.mean():.4f}, max {pos_err.max():.4f}")
    print(f"focal: COLMAP {f_col:.2f} px at width {w_col} (model id "
          f"{model_id}); poses_bounds {f:.2f} px at width {w:.0f}, i.e. "
          f"{f * w_col / w:.2f} px at width {w_col}")


if __name__ == "__main__":
    main()
