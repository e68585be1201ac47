#!/usr/bin/env python3
"""Train the tiny preset on libnerf's built-in scene, from Python.

Writes the built-in scene, trains a tiny model on its training views with
a progress line, reports the PSNR on the test views and renders a few of
them to PNG files:

    PYTHONPATH=bindings/python NERF_LIBRARY=build/release/lib/libnerf.so.0 \\
        python3 bindings/python/examples/train_builtin.py --out /tmp/nerf-demo

Works with or without NumPy.  Ctrl-C stops training after the current step
and still evaluates what was learnt.
"""

import argparse
import os
import sys
import time

import nerf


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="nerf-builtin",
                   help="output folder (default: %(default)s)")
    p.add_argument("--steps", type=int, default=500,
                   help="training steps (default: %(default)s)")
    p.add_argument("--size", type=int, default=64,
                   help="image width and height in pixels "
                        "(default: %(default)s)")
    p.add_argument("--views", type=int, default=40,
                   help="training views (default: %(default)s)")
    p.add_argument("--test-views", type=int, default=8,
                   help="test views (default: %(default)s)")
    p.add_argument("--batch", type=int, default=512,
                   help="rays per step (default: %(default)s)")
    p.add_argument("--lr", type=float, default=5e-3,
                   help="initial learning rate, decaying tenfold over the "
                        "run (default: %(default)s)")
    p.add_argument("--renders", type=int, default=3,
                   help="test views to save as PNG (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0)
    return p.parse_args(argv)


class ProgressLine:
    """Progress on one rewritten line on a terminal, plain lines (about
    ten per run) otherwise, so that logs stay readable."""

    def __init__(self, stream=sys.stderr):
        self.stream = stream
        self.tty = stream.isatty()
        self.last_line = -1

    def __call__(self, p: nerf.Progress) -> None:
        text = "step %d/%d  loss %.5f  psnr %.2f dB  %.1f s" % (
            p.done, p.total, p.loss, p.psnr, p.elapsed)
        if self.tty:
            self.stream.write("\r" + text)
            self.stream.flush()
            return
        tenth = int(10 * p.done / p.total) if p.total else 10
        if tenth != self.last_line or p.done == p.total:
            self.last_line = tenth
            self.stream.write(text + "\n")

    def finish(self) -> None:
        if self.tty:
            self.stream.write("\n")


def evaluate(renderer, test, out_dir, n_renders):
    """Mean PSNR over the test views; saves the first renders as PNG."""
    total = 0.0
    for i in range(len(test)):
        rgb = renderer.render_image(test.camera(i), depth=False,
                                    opacity=False).rgb
        total += nerf.psnr(rgb, test.image(i))
        if i < n_renders:
            path = os.path.join(out_dir, "test_%03d.png" % i)
            nerf.write_png(path, rgb)
            print("wrote %s" % path)
    return total / len(test)


def main(argv=None) -> int:
    args = parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    scene = os.path.join(args.out, "scene")
    print("libnerf %s (%s)" % (nerf.version_string(),
                               "numpy" if nerf.HAVE_NUMPY else "no numpy"))
    start = time.monotonic()
    nerf.write_scene(scene, width=args.size, height=args.size,
                     n_train=args.views, n_val=1, n_test=args.test_views)
    print("wrote the built-in scene to %s in %.1f s"
          % (scene, time.monotonic() - start))

    with nerf.Dataset(scene, "train") as train, \
            nerf.Dataset(scene, "test") as test, \
            nerf.Model(preset="tiny", seed=args.seed) as model, \
            nerf.Sampler.for_dataset(train, preset="tiny",
                                     seed=args.seed) as sampler:
        # The paper's schedule: a tenfold exponential decay over the run.
        model.set_param("learning_rate", args.lr)
        model.set_param("learning_rate_final", args.lr / 10)
        model.set_param("decay_steps", max(args.steps, 1))
        line = ProgressLine()
        with nerf.Trainer(model, train, sampler, batch_rays=args.batch,
                          precrop_steps=min(500, args.steps // 4)) as trainer:
            try:
                stats = trainer.run(args.steps, progress=line)
                line.finish()
                print("trained %d steps: train psnr %.2f dB"
                      % (stats.step, stats.psnr))
            except KeyboardInterrupt:
                line.finish()
                print("interrupted at step %d" % model.step)
        with nerf.Renderer(model, sampler, white_background=1) as renderer:
            score = evaluate(renderer, test, args.out, args.renders)
        print("test psnr %.2f dB over %d views" % (score, len(test)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
