#!/usr/bin/env python3
"""tutorial.py: the program docs/tutorial-python.md walks through.

It writes libnerf's built-in scene, trains a small NeRF on it, reports the
PSNR on held-out views and renders an orbit around the scene, as
examples/tutorial.c does in C:

    python3 examples/tutorial.py OUT_DIR [STEPS [FRAMES [PRESET]]]

PRESET is tiny (the default), fast or reference; the run is the one
`nerf-train --preset PRESET --steps STEPS` makes on OUT_DIR/scene, bit for
bit.  Everything it writes goes to OUT_DIR: scene/, model.nerf and
orbit_NNN.png.
"""

import math
import os
import sys

import nerf

SIZE = 64  # pixels, for the scene's images and the orbit


def on_progress(p):
    """Called by Trainer.run() after every step; a true result stops it."""
    if p.done % 100 == 0 or p.done == p.total:
        print("step %4d/%d  loss %.5f  psnr %5.2f dB  %.0f s"
              % (p.done, p.total, p.loss, p.psnr, p.elapsed), flush=True)


def orbit_camera(i, n, focal):
    """A camera on a circle of radius 4 at 30 degrees elevation, looking at
    the origin with z up, as the scene's own cameras do."""
    az, elev = 2 * math.pi * i / n, math.pi / 6
    eye = (4 * math.cos(elev) * math.cos(az),
           4 * math.cos(elev) * math.sin(az),
           4 * math.sin(elev))
    cam = nerf.Camera(width=SIZE, height=SIZE, fx=focal, fy=focal,
                      cx=SIZE / 2, cy=SIZE / 2)
    return cam.look_at(eye, target=(0, 0, 0), up=(0, 0, 1))


def run(out, steps, frames, preset):
    os.makedirs(out, exist_ok=True)
    scene_dir = os.path.join(out, "scene")

    # 1. The data: the built-in scene, written as a Blender dataset.
    nerf.write_scene(scene_dir, width=SIZE, height=SIZE,
                     n_train=60, n_val=0, n_test=4)
    train = nerf.Dataset(scene_dir, "train")
    test = nerf.Dataset(scene_dir, "test")

    # 2. The model: a preset's network and learning rate, placed in the
    # dataset's scene (which matters to the fast preset's grids), with the
    # fastest fp32 products this machine has.  The learning rate decays
    # tenfold over the run.
    model = nerf.Model.for_dataset(train, preset, matmul="fp32-fastest")
    model.set_param("decay_steps", steps)

    # 3. The sampler: the model's sampling (the preset's sample counts, or
    # its march through the occupancy grid) between the dataset's near and
    # far bounds.
    sampler = nerf.Sampler.for_model(model, train, training=True)

    # 4. Training: batches of random rays across all training images, as
    # many as the model's preset takes.
    trainer = nerf.Trainer.for_model(model, train, sampler)
    trainer.run(steps, progress=on_progress)
    path = os.path.join(out, "model.nerf")
    model.save(path)
    print("saved %s" % path)

    # 5. Evaluation: render each test view, as the model records it is
    # rendered (the scene's background; a fast model's finer march), and
    # compare it with its image.
    renderer = nerf.Renderer(model, nerf.Sampler.for_model(model, test))
    total = 0.0
    for i in range(len(test)):
        rgb = renderer.render_image(test.camera(i), depth=False,
                                    opacity=False).rgb
        total += nerf.psnr(rgb, test.image(i))
    print("test PSNR %.2f dB over %d views" % (total / len(test), len(test)))

    # 6. An orbit: new views from all around, with the training focal.
    focal = train.camera(0).fx
    for i in range(frames):
        rgb = renderer.render_image(orbit_camera(i, frames, focal),
                                    depth=False, opacity=False).rgb
        nerf.write_png(os.path.join(out, "orbit_%03d.png" % i), rgb)
    print("wrote %d orbit views to %s/orbit_*.png" % (frames, out))


def main(argv):
    if not 2 <= len(argv) <= 5:
        print("usage: tutorial.py OUT_DIR [STEPS [FRAMES [PRESET]]]",
              file=sys.stderr)
        return 2
    steps = int(argv[2]) if len(argv) > 2 else 1000
    frames = int(argv[3]) if len(argv) > 3 else 12
    preset = argv[4] if len(argv) > 4 else "tiny"
    if steps < 1 or frames < 1 or preset not in ("tiny", "fast", "reference"):
        print("tutorial.py: STEPS and FRAMES must be at least 1, PRESET "
              "tiny, fast or reference", file=sys.stderr)
        return 2
    try:
        run(argv[1], steps, frames, preset)
    except nerf.NerfError as e:
        # The library's message says what failed: the file, the field.
        print("tutorial.py: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
