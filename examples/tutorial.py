#!/usr/bin/env python3
"""tutorial.py: the program docs/tutorial-python.md walks through.

It writes libnerf's built-in scene, trains a small NeRF on it, reports the
PSNR on held-out views and renders an orbit around the scene, as
examples/tutorial.c does in C:

    python3 examples/tutorial.py OUT_DIR [STEPS [FRAMES]]

Everything it writes goes to OUT_DIR: scene/, model.nerf and
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


def run(out, steps, frames):
    os.makedirs(out, exist_ok=True)
    scene_dir = os.path.join(out, "scene")

    # 1. The data: the built-in scene, written as a Blender dataset.
    nerf.write_scene(scene_dir, width=SIZE, height=SIZE,
                     n_train=60, n_val=0, n_test=4)
    train = nerf.Dataset(scene_dir, "train")
    test = nerf.Dataset(scene_dir, "test")

    # 2. The model: the tiny preset, with a learning rate suited to it
    # that decays tenfold over the run.
    model = nerf.Model(preset="tiny")
    model.set_param("learning_rate", 5e-3)
    model.set_param("learning_rate_final", 5e-4)
    model.set_param("decay_steps", steps)

    # 3. The sampler: the tiny preset's sample counts, between the
    # dataset's near and far bounds.
    sampler = nerf.Sampler.for_dataset(train, preset="tiny")

    # 4. Training: batches of random rays across all training images.
    trainer = nerf.Trainer(model, train, sampler, batch_rays=256)
    trainer.run(steps, progress=on_progress)
    path = os.path.join(out, "model.nerf")
    model.save(path)
    print("saved %s" % path)

    # 5. Evaluation: render each test view and compare it with its image.
    renderer = nerf.Renderer(model, sampler, white_background=1)
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
    if not 2 <= len(argv) <= 4:
        print("usage: tutorial.py OUT_DIR [STEPS [FRAMES]]", file=sys.stderr)
        return 2
    steps = int(argv[2]) if len(argv) > 2 else 1000
    frames = int(argv[3]) if len(argv) > 3 else 12
    if steps < 1 or frames < 1:
        print("tutorial.py: STEPS and FRAMES must be at least 1",
              file=sys.stderr)
        return 2
    try:
        run(argv[1], steps, frames)
    except nerf.NerfError as e:
        # The library's message says what failed: the file, the field.
        print("tutorial.py: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
