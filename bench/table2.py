#!/usr/bin/python3
"""The ablations of the NeRF paper's Table 2 on Blender lego, in one command.

    /usr/bin/python3 bench/table2.py --data DIR

(after the build: the binding in bindings/python finds build/release's
library, or NERF_LIBRARY's)

trains and evaluates the table's nine rows at a reduced protocol (stated at
the top of the output), prints PSNR and SSIM per row beside the paper's
figures, then says which of the comparisons the paper's argument rests on
hold at this protocol.  --quick runs every row for a few steps on a few test
views, to check the script end to end in minutes; its figures mean nothing.
docs/ablations.md shows a full run and how the protocol was chosen.

Each row is the complete model with only what the paper's row changes
changed: the rows share the network, image size, steps, batch and
learning-rate schedule, and the seed unless the row's networks start dead
at it (starts_alive()).
"""

import argparse
import os
import platform
import shlex
import sys
import time

# The binding of this checkout, unless one is installed or on PYTHONPATH.
sys.path.append(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                             "..", "bindings", "python"))
import nerf  # noqa: E402

# The reduced protocol, chosen so that the nine rows and their evaluation
# take about ninety minutes on two cores (docs/ablations.md, "Protocol",
# says how it was timed).  The paper trains 800 x 800 images, networks 256
# wide, 4096 rays a step for 100k to 300k steps.
PROTOCOL = {
    "downscale": 8,      # 800 x 800 -> 100 x 100
    "width": 64,         # trunk; the view branch is half of it, as 256/128
    "steps": 1200,
    "batch": 512,
    "lr": 5e-3,          # the tiny preset's, which a 64-wide network takes
    "test_every": 10,    # every 10th of the 200 test views: 20 views
    "seed": 0,
}
QUICK = dict(PROTOCOL, downscale=16, steps=10, batch=64, test_every=50)

# The paper's Table 2: (name, PSNR, SSIM, LPIPS), averages over its eight
# realistic synthetic scenes, not lego alone.  Then what the row changes
# from the complete model: model fields, (N_c, N_f), training images kept
# (every k-th of the 100).
COMPLETE = {"pos_frequencies": 10, "dir_frequencies": 4, "use_viewdirs": 1,
            "use_fine": 1}
ROWS = [
    ("No PE, VD, H", 26.67, 0.906, 0.136,
     {"pos_frequencies": 0, "dir_frequencies": 0, "use_viewdirs": 0,
      "use_fine": 0}, (256, 0), 1),
    ("No Pos. Encoding", 28.77, 0.924, 0.108,
     {"pos_frequencies": 0, "dir_frequencies": 0}, (64, 128), 1),
    ("No View Dependence", 27.66, 0.925, 0.117,
     {"use_viewdirs": 0}, (64, 128), 1),
    ("No Hierarchical", 30.06, 0.938, 0.109,
     {"use_fine": 0}, (256, 0), 1),
    ("Far Fewer Images (25)", 27.78, 0.925, 0.107, {}, (64, 128), 4),
    ("Fewer Images (50)", 29.79, 0.940, 0.096, {}, (64, 128), 2),
    ("Fewer Frequencies (L=5)", 30.59, 0.944, 0.088,
     {"pos_frequencies": 5}, (64, 128), 1),
    ("More Frequencies (L=15)", 30.81, 0.946, 0.096,
     {"pos_frequencies": 15}, (64, 128), 1),
    ("Complete Model", 31.01, 0.947, 0.081, {}, (64, 128), 1),
]
TABLE1_LEGO = (32.54, 0.961, 0.050)

# The comparisons the paper's argument rests on: (what, better row, worse
# row), 0-based indices into ROWS.
COMPLETE_ROW = 8
CHECKS = [("complete > no PE, VD, H", COMPLETE_ROW, 0),
          ("complete > no positional encoding", COMPLETE_ROW, 1),
          ("complete > no view dependence", COMPLETE_ROW, 2),
          ("complete > no hierarchical sampling", COMPLETE_ROW, 3),
          ("50 images > 25 images", 5, 4),
          ("100 images > 50 images", COMPLETE_ROW, 5),
          ("L = 10 > L = 5", COMPLETE_ROW, 6),
          ("L = 10 > L = 15", COMPLETE_ROW, 7)]


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data", required=True,
                   help="the Blender lego folder (transforms_*.json)")
    p.add_argument("--quick", action="store_true",
                   help="every row for a few steps on a few test views: "
                        "checks the script, not the paper")
    p.add_argument("--rows", default=None,
                   help="comma-separated row numbers, 1..9 (default all); "
                        "the ordering checks need all nine")
    p.add_argument("--steps", type=int, default=None,
                   help="steps a row, in place of the protocol's (for "
                        "timing it)")
    p.add_argument("--downscale", type=int, default=None,
                   help="images reduced this many times, in place of the "
                        "protocol's 8 (to see what the images' size does "
                        "to a row)")
    p.add_argument("--no-eval", action="store_true",
                   help="train only, no test renders (for timing)")
    return p.parse_args(argv)


def machine_line():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return "%s, %d cores; libnerf %s (%s)" % (
        cpu, os.cpu_count() or 0, nerf.version_string(), nerf.build_info())


def protocol_lines(proto, quick, n_test, size):
    return [
        "protocol%s: lego at %d x %d (downscale %d), %d test views (every "
        "%dth of 200)," % (" (--quick: not a result)" if quick else "",
                           size[0], size[1], proto["downscale"], n_test,
                           proto["test_every"]),
        "  the paper's network shape (8 layers, skip at 5, view branch) "
        "%d wide (view %d),"
        % (proto["width"], proto["width"] // 2),
        "  %d steps of %d rays, learning rate %g decaying tenfold;"
        % (proto["steps"], proto["batch"], proto["lr"]),
        "  samples (N_c, N_f) as the paper's rows; seed %d, or the first "
        "after it whose networks start with" % proto["seed"],
        "  some positive density (a row's seed is in the table)",
    ]


# Points spread over the cube lego lies in (Blender scenes: near 2, far 6
# from cameras about 4 away), where a network that can learn must have some
# positive density.
GRID = [[(i + 0.5) / 8 * 3 - 1.5, (j + 0.5) / 8 * 3 - 1.5,
         (k + 0.5) / 8 * 3 - 1.5]
        for i in range(8) for j in range(8) for k in range(8)]
SEEDS_TRIED = 16


def starts_alive(model):
    """Whether each of the model's networks has a positive density
    somewhere in GRID.  A ReLU density that is nowhere positive gets no
    gradient, and the network never learns; with raw coordinates (rows 1
    and 2) a small network starts so at about one seed in two, since its
    density then varies slowly and often has one sign over the whole
    scene.  The start is set by the seed alone."""
    dirs = [[0.0, 0.0, 1.0]] * len(GRID)
    nets = ["coarse", "fine"] if model.options.use_fine else ["coarse"]
    return all(max(model.query(GRID, dirs, network=n)[1]) > 0 for n in nets)


def make_model(opts, proto):
    """The row's model from the protocol's seed, or from the first seed
    after it whose networks start alive (starts_alive): a network that
    cannot learn says nothing about the ablation.  Returns (model, seed)."""
    for seed in range(proto["seed"], proto["seed"] + SEEDS_TRIED):
        model = nerf.Model(preset="reference", seed=seed,
                           width=proto["width"],
                           view_width=proto["width"] // 2, **opts)
        if starts_alive(model):
            return model, seed
        model.close()
    raise RuntimeError("no seed of %d to %d starts alive"
                       % (proto["seed"], seed))


def train_row(row, proto, data, test, quiet):
    name, _, _, _, fields, (n_coarse, n_fine), every = row
    opts = dict(COMPLETE, **fields)
    train = nerf.Dataset(data, "train", downscale=proto["downscale"],
                         skip=every)
    model, seed = make_model(opts, proto)
    model.set_param("learning_rate", proto["lr"])
    model.set_param("learning_rate_final", proto["lr"] / 10)
    model.set_param("decay_steps", proto["steps"])
    sampler = nerf.Sampler.for_model(model, train, training=True,
                                     seed=seed, n_coarse=n_coarse,
                                     n_fine=n_fine)
    first = []

    def note_first(p):
        if not first:
            first.append(p.psnr)

    t0 = time.monotonic()
    with nerf.Trainer.for_model(model, train, sampler,
                                batch_rays=proto["batch"]) as trainer:
        stats = trainer.run(proto["steps"], progress=note_first)
    t_train = time.monotonic() - t0
    # A network alive at the start can still die in training; such a row
    # says nothing about the ablation either, so it is named rather than
    # left to pass as a result.
    # --quick's few steps leave every row unlearnt: not judged there.
    dead = (bool(first) and stats.psnr < first[0] + 1.0
            and proto["steps"] >= 100)
    if not quiet:
        print("  %-24s %d images, seed %d, trained %d steps in %.0f s "
              "(train PSNR %.2f%s)" % (name, len(train), seed,
                                       proto["steps"], t_train, stats.psnr,
                                       ", did not learn" if dead else ""),
              file=sys.stderr, flush=True)
    if test is None:
        return None, None, t_train, 0.0, dead, seed
    t0 = time.monotonic()
    render_sampler = nerf.Sampler.for_model(model, test, n_coarse=n_coarse,
                                            n_fine=n_fine)
    renderer = nerf.Renderer(model, render_sampler, white_background=1)
    psnr = ssim = 0.0
    for i in range(len(test)):
        out = renderer.render_image(test.camera(i))
        truth = test.image(i)
        psnr += nerf.psnr(out.rgb, truth)
        ssim += nerf.ssim(out.rgb, truth)
    t_eval = time.monotonic() - t0
    renderer.close()
    return (psnr / len(test), ssim / len(test), t_train, t_eval, dead,
            seed)


def main(argv=None):
    if argv is None:
        argv = sys.argv[1:]
    args = parse_args(argv)
    proto = dict(QUICK if args.quick else PROTOCOL)
    if args.steps:
        proto["steps"] = args.steps
    if args.downscale:
        proto["downscale"] = args.downscale
    picked = list(range(len(ROWS)))
    if args.rows:
        try:
            picked = [int(r) - 1 for r in args.rows.split(",")]
        except ValueError:
            picked = [-1]
        if any(r < 0 or r >= len(ROWS) for r in picked):
            print("table2: --rows takes numbers 1..%d" % len(ROWS),
                  file=sys.stderr)
            return 2
    if not os.path.isfile(os.path.join(args.data, "transforms_test.json")):
        print("table2: %s holds no Blender scene (transforms_test.json): "
              "give --data the lego folder" % args.data, file=sys.stderr)
        return 2
    test = None
    if not args.no_eval:
        test = nerf.Dataset(args.data, "test", downscale=proto["downscale"],
                            skip=proto["test_every"])
        size = test.image_size
        n_test = len(test)
    else:
        size, n_test = (800 // proto["downscale"],) * 2, 0
    for line in protocol_lines(proto, args.quick, n_test, size):
        print(line)
    print("machine: " + machine_line())
    # As given, so that the page's copy of the output says how to rerun it.
    print("command: bench/table2.py " + " ".join(shlex.quote(a) for a in argv))
    print(flush=True)

    results = {}
    t_all = time.monotonic()
    for r in picked:
        results[r] = train_row(ROWS[r], proto, args.data, test, False)
    minutes = (time.monotonic() - t_all) / 60

    print("%-26s %-8s %4s %6s %6s | %6s %6s %6s   %s" % (
        "row (paper: 8-scene mean)", "(Nc,Nf)", "seed", "PSNR", "SSIM",
        "paper", "SSIM", "LPIPS", "train+eval s"))
    for r in picked:
        name, p_psnr, p_ssim, p_lpips, _, (nc, nf), _ = ROWS[r]
        psnr, ssim, t_train, t_eval, dead, seed = results[r]
        samples = "(%d,%s)" % (nc, nf if nf else "-")
        ours = ("%6.2f %6.3f" % (psnr, ssim)) if psnr is not None \
            else "%6s %6s" % ("-", "-")
        print("%d %-24s %-8s %4d %s | %6.2f %6.3f %6.3f   %.0f+%.0f%s" % (
            r + 1, name, samples, seed, ours, p_psnr, p_ssim, p_lpips,
            t_train, t_eval, "  did not learn" if dead else ""))
    print("Table 1, lego (NeRF, full protocol): PSNR %.2f, SSIM %.3f, "
          "LPIPS %.3f; the complete model's row above is its counterpart "
          "at this protocol" % TABLE1_LEGO)
    print("%.1f minutes in all" % minutes)

    if test is None or len(picked) != len(ROWS):
        print("\nordering checks: need all nine rows evaluated")
        return 0
    print("\nordering (test PSNR; the paper's holds for every pair):")
    agree = 0
    for what, hi, lo in CHECKS:
        d = results[hi][0] - results[lo][0]
        ok = d > 0
        agree += ok
        print("  %-38s %+6.2f dB  %s (paper %+.2f dB)" % (
            what, d, "agrees" if ok else "DISAGREES",
            ROWS[hi][1] - ROWS[lo][1]))
    print("%d of %d comparisons agree with the paper at this protocol"
          % (agree, len(CHECKS)))
    dead = [ROWS[r][0] for r in picked if results[r][4]]
    if dead:
        print("rows that did not learn (a dead start, not the ablation's "
              "effect): " + ", ".join(dead))
    return 0


if __name__ == "__main__":
    sys.exit(main())
