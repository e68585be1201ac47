#!/usr/bin/env python3
"""Why COLMAP left photos out: scripts/colmap-train.sh runs this after the
mapper, so that a user never has to read COLMAP's log to learn that part
of a capture was dropped.

    colmap-explain.py DATABASE SPARSE_DIR KEPT MATCHER

DATABASE is COLMAP's database.db, SPARSE_DIR the mapper's output folder
(its reconstructions 0, 1, ...), KEPT the name of the one kept (the most
photos registered; "" when the mapper made none), MATCHER "exhaustive" or
"sequential".  Prints, on stdout: the reconstructions and which is kept
and why; each photo left out of the kept one with what is known of it
(features found, matches and geometrically verified inlier matches with
the placed photos, another reconstruction it is in) and the likely cause;
then the next step that usually helps.  Exit status 0, or 2 when the
database cannot be read.

Reads COLMAP 3.8's database (tables images, keypoints, matches,
two_view_geometries) with sqlite3 and the models' images.bin (or
images.txt), the formats of COLMAP's documentation.
"""

import os
import sqlite3
import struct
import sys

# COLMAP numbers a pair of images (id1 < id2) as id1 * this + id2.
PAIR_BASE = 2147483647
# The mapper's defaults (COLMAP 3.8): a pair counts as overlapping with
# at least 15 verified inliers (Mapper.min_num_matches,
# TwoViewGeometry's min_num_inliers).
MIN_INLIERS = 15
# Fewer SIFT features than this in a photo rarely leave 15 inliers with
# any other: a smooth, dark or blurred photo.
FEW_FEATURES = 100
# The mapper keeps no reconstruction of fewer photos than this
# (Mapper.min_model_size, COLMAP 3.8's default).
MIN_MODEL_SIZE = 10


def pair_images(pair_id):
    id2 = pair_id % PAIR_BASE
    return (pair_id - id2) // PAIR_BASE, id2


def read_names_bin(path):
    """The image names of a model's images.bin."""
    names = []
    with open(path, "rb") as f:
        (count,) = struct.unpack("<Q", f.read(8))
        for _ in range(count):
            # image_id, qvec (4 doubles), tvec (3 doubles), camera_id
            f.read(4 + 8 * 7 + 4)
            name = bytearray()
            while True:
                c = f.read(1)
                if not c or c == b"\0":
                    break
                name += c
            names.append(name.decode("utf-8", "replace"))
            (points,) = struct.unpack("<Q", f.read(8))
            f.seek(24 * points, os.SEEK_CUR)  # x, y, point3D_id each
    return names


def read_names_txt(path):
    names = []
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = [l for l in f if l.strip() and not l.startswith("#")]
    # Two lines an image: its pose and name, then its 2D points.
    for line in lines[0::2]:
        parts = line.split()
        if len(parts) >= 10:
            names.append(" ".join(parts[9:]))
    return names


def read_models(sparse):
    """{model name: set of image names} for each reconstruction."""
    models = {}
    if not os.path.isdir(sparse):
        return models
    for entry in sorted(os.listdir(sparse)):
        folder = os.path.join(sparse, entry)
        try:
            if os.path.isfile(os.path.join(folder, "images.bin")):
                models[entry] = set(read_names_bin(
                    os.path.join(folder, "images.bin")))
            elif os.path.isfile(os.path.join(folder, "images.txt")):
                models[entry] = set(read_names_txt(
                    os.path.join(folder, "images.txt")))
        except (OSError, struct.error):
            continue
    return models


def read_database(path):
    db = sqlite3.connect("file:%s?mode=ro" % path, uri=True)
    try:
        names = dict(db.execute("SELECT image_id, name FROM images"))
        features = dict(db.execute("SELECT image_id, rows FROM keypoints"))
        raw = {}
        for pair_id, rows in db.execute("SELECT pair_id, rows FROM matches"):
            raw[pair_images(pair_id)] = rows or 0
        verified = {}
        for pair_id, rows in db.execute(
                "SELECT pair_id, rows FROM two_view_geometries"):
            verified[pair_images(pair_id)] = rows or 0
    finally:
        db.close()
    return names, features, raw, verified


def plural(n, word):
    return "%d %s%s" % (n, word, "" if n == 1 else "s")


def explain(database, sparse, kept, matcher):
    names, features, raw, verified = read_database(database)
    models = read_models(sparse)
    out = []
    n = len(names)
    if len(models) > 1:
        sizes = ", ".join("%s (%s)" % (k, plural(len(v), "photo"))
                          for k, v in sorted(models.items(),
                                             key=lambda kv: -len(kv[1])))
        out.append("COLMAP made %d separate reconstructions: %s; kept "
                   "%s, which has the most photos registered (the others "
                   "share too few matched points with it to be joined)."
                   % (len(models), sizes, kept))
    placed_names = models.get(kept, set())
    by_name = {v: k for k, v in names.items()}
    placed = {by_name[x] for x in placed_names if x in by_name}
    left = sorted((i for i in names if i not in placed),
                  key=lambda i: names[i])
    if not left:
        return out
    counts = {"few": 0, "unmatched": 0, "unverified": 0, "elsewhere": 0,
              "unregistered": 0, "nomodel": 0}
    out.append("%s of %d not placed%s:" % (
        plural(len(left), "photo"), n,
        " in reconstruction %s" % kept if kept else ""))
    # Without a reconstruction, what a photo shares with any other.
    label = "the placed photos" if placed else "the other photos"
    for i in left:
        f = features.get(i, 0)
        ref = placed if placed else set(names) - {i}
        with_placed = [(j, raw.get(tuple(sorted((i, j))), 0),
                        verified.get(tuple(sorted((i, j))), 0))
                       for j in ref]
        tried = [p for p in with_placed
                 if tuple(sorted((i, p[0]))) in raw or
                 tuple(sorted((i, p[0]))) in verified]
        n_raw = sum(p[1] for p in with_placed)
        n_inl = sum(p[2] for p in with_placed)
        good = [p for p in with_placed if p[2] >= MIN_INLIERS]
        best = max(with_placed, key=lambda p: p[2], default=None)
        other = [k for k, v in models.items()
                 if k != kept and names[i] in v]
        facts = "%s found" % plural(f, "feature")
        if ref:
            facts += ("; %d matches, %d verified inliers with %s"
                      % (n_raw, n_inl, label))
            if best is not None and best[2] > 0:
                facts += " (most: %d with %s)" % (best[2], names[best[0]])
        if other:
            counts["elsewhere"] += 1
            why = ("placed in reconstruction %s instead, which was not "
                   "joined to %s" % (other[0], kept))
        elif f < FEW_FEATURES:
            counts["few"] += 1
            why = ("too few features to match: the photo is smooth, dark "
                   "or blurred")
        elif ref and not tried:
            counts["unmatched"] += 1
            why = ("never compared with a placed photo (sequential "
                   "matching compares each photo with its neighbours in "
                   "name order only)" if matcher == "sequential" else
                   "not compared with any placed photo")
        elif not good:
            counts["unverified"] += 1
            why = ("none of %s shares %d or more verified matches with "
                   "it: it overlaps too little with them, or shows "
                   "something else" % (label, MIN_INLIERS))
        elif not placed:
            counts["nomodel"] += 1
            why = ("it overlaps with %s, but the mapper kept no "
                   "reconstruction: it keeps none of fewer than %d photos "
                   "and needs two that overlap well from viewpoints far "
                   "enough apart to start from"
                   % (plural(len(good), "other photo"), MIN_MODEL_SIZE))
        else:
            counts["unregistered"] += 1
            why = ("it overlaps with %s, but the mapper could not fit its "
                   "pose (a lens the camera model does not describe, or "
                   "too few of its matches on placed points)"
                   % plural(len(good), ("placed" if placed else "other")
                            + " photo"))
        out.append("  %s: %s; %s" % (names[i], facts, why))
    steps = []
    if counts["unmatched"] or (matcher == "sequential" and
                               (counts["elsewhere"] or counts["unverified"])):
        steps.append("--matcher exhaustive compares every pair of photos, "
                     "not only neighbours (slower: it grows with the "
                     "square of the count)")
    if counts["few"] or counts["unverified"] or counts["elsewhere"]:
        steps.append("more overlap: photos (or video frames) closer "
                     "together, each sharing most of its view with the "
                     "next, of textured surfaces, sharp and well lit; "
                     "remove photos of something else")
    if counts["nomodel"]:
        steps.append("more photos (COLMAP keeps no reconstruction of fewer "
                     "than %d), some of them from viewpoints further apart"
                     % MIN_MODEL_SIZE)
    if counts["unregistered"]:
        steps.append("another camera model: --camera-model OPENCV (or "
                     "RADIAL) for a wide-angle or fisheye lens")
    if steps:
        out.append("What usually helps: " + "; or ".join(steps) + ".")
    return out


def main(argv):
    if len(argv) != 5:
        sys.stderr.write(__doc__)
        return 2
    database, sparse, kept, matcher = argv[1:]
    try:
        lines = explain(database, sparse, kept, matcher)
    except (sqlite3.Error, OSError) as e:
        sys.stderr.write("colmap-explain: %s: cannot be read: %s\n"
                         % (database, e))
        return 2
    for line in lines:
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
