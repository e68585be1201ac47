#!/usr/bin/python3
"""Projected strong scaling of data-parallel training (docs/distributed.md).

A step of B rays on p nodes takes
    T(p) = T_par / p + T_serial + T_comm(p)
where T_par + T_serial = T(1) is one node's step (measured: --fast-step,
--reference-step), T_serial the part every node repeats whole (the Adam
update over all weights, the occupancy grid's refresh), and T_comm the
gradient exchange:
    ring (reduce-scatter + allgather):  2 (p-1) alpha + 2 (p-1)/p * n * beta
    recursive doubling:                 log2(p) * (alpha + n * beta)
    pairs through a ring allgather:     (p-1) alpha + (p-1)/p * P * beta
with n the bytes of the gradient, P the bytes of every node's (index,
value) pairs, alpha the latency of one message and beta = 8 / bandwidth.
The exchange takes the cheaper of ring and recursive doubling (as Open
MPI's fixed rules do: recursive doubling for small messages, ring-based
ones for large).  Efficiency E(p) = T(1) / (p T(p)).

Usage: distributed-model.py [--svg FILE] [--fast-step S] [--reference-step S]
       [--fast-serial F] [--reference-serial F] [--alpha S]
Prints a Markdown table of E(p) and writes the plot.  The step times'
defaults are PLACEHOLDERS, not measurements: pass the measured ones
(scripts/bench-mpi.sh prints them).
"""

import argparse
import math
import sys

# Parameter counts (bench/bench_exchange prints them).
FAST_PARAMS = 12207469
FAST_TABLE = 12197850  # hash-table entries; the other 9619 are layers
REFERENCE_PARAMS = 1191688
# Table entries a fast step touches, per ray, measured on the built-in
# scene at 1024 rays a step once the occupancy grid has settled (about 48
# samples a ray at step 256, 2.82 million entries): bench/bench_exchange
# 256 1024 64.  Workers' sets overlap, so their pairs add up to more than
# the batch's; sparse() assumes twice as many.
FAST_TOUCHED_PER_RAY = 2.82e6 / 1024
BATCH = 1024

NODES = [2, 4, 8, 16, 32, 64]
NETWORKS = [10, 25, 100]  # Gb/s

# PLACEHOLDERS (one node's step of 1024 rays, in seconds): replace with
# measured values.
PLACEHOLDER_FAST_STEP = 0.060
PLACEHOLDER_REFERENCE_STEP = 1.5


def ring(p, nbytes, alpha, beta):
    return 2 * (p - 1) * alpha + 2 * (p - 1) / p * nbytes * beta


def recursive_doubling(p, nbytes, alpha, beta):
    return math.log2(p) * (alpha + nbytes * beta)


def allreduce(p, nbytes, alpha, beta):
    return min(ring(p, nbytes, alpha, beta),
               recursive_doubling(p, nbytes, alpha, beta))


def sparse(p, alpha, beta):
    """Layers by allreduce, table entries as 8-byte pairs gathered by all.
    Each node's B/p rays touch their own entries; the pairs of all nodes
    are at most the batch's touches, at most p whole tables."""
    layers = 4 * (FAST_PARAMS - FAST_TABLE)
    pairs = 8 * min(BATCH * FAST_TOUCHED_PER_RAY * 2.0, p * FAST_TABLE)
    gather = (p - 1) * alpha + (p - 1) / p * pairs * beta
    return allreduce(p, layers, alpha, beta) + gather


def efficiency(p, step, serial, comm):
    t1 = step
    tp = step * (1 - serial) / p + step * serial + comm
    return t1 / (p * tp)


def table(args):
    rows = []
    for name, step, params, serial in (
            ("fast", args.fast_step, FAST_PARAMS, args.fast_serial),
            ("reference", args.reference_step, REFERENCE_PARAMS,
             args.reference_serial)):
        for gbs in NETWORKS:
            beta = 8 / (gbs * 1e9)
            effs = []
            for p in NODES:
                comm = allreduce(p, 4 * params, args.alpha, beta)
                if name == "fast":
                    comm = min(comm, sparse(p, args.alpha, beta))
                effs.append(efficiency(p, step, serial, comm))
            rows.append((name, gbs, effs))
    return rows


def write_svg(path, rows, args):
    w, h = 760, 330
    pw, ph = 320, 220
    colors = {10: "#c0392b", 25: "#2471a3", 100: "#1e8449"}
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
           'font-family="sans-serif" font-size="11">' % (w, h),
           '<rect width="100%" height="100%" fill="white"/>']
    for k, name in enumerate(("fast", "reference")):
        x0, y0 = 50 + k * (pw + 60), 40
        step = args.fast_step if name == "fast" else args.reference_step
        out.append('<text x="%d" y="%d" font-size="13">%s preset, %g s a '
                   'step on one node%s</text>' % (
                       x0, y0 - 15, name, step,
                       " (placeholder)" if step in (
                           PLACEHOLDER_FAST_STEP,
                           PLACEHOLDER_REFERENCE_STEP) else ""))
        out.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" '
                   'stroke="black"/>' % (x0, y0, pw, ph))
        for e in (0.25, 0.5, 0.75, 1.0):
            y = y0 + ph - e * ph
            out.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" '
                       'stroke="#ddd"/>' % (x0, x0 + pw, y, y))
            out.append('<text x="%d" y="%.1f" text-anchor="end">%d%%</text>'
                       % (x0 - 4, y + 4, round(100 * e)))
        for i, p in enumerate(NODES):
            x = x0 + pw * i / (len(NODES) - 1)
            out.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>'
                       % (x, y0 + ph + 14, p))
        out.append('<text x="%d" y="%d" text-anchor="middle">nodes</text>'
                   % (x0 + pw // 2, y0 + ph + 30))
        for pname, gbs, effs in rows:
            if pname != name:
                continue
            pts = " ".join("%.1f,%.1f" % (x0 + pw * i / (len(NODES) - 1),
                                          y0 + ph - min(e, 1.0) * ph)
                           for i, e in enumerate(effs))
            out.append('<polyline points="%s" fill="none" stroke="%s" '
                       'stroke-width="2"/>' % (pts, colors[gbs]))
        for j, gbs in enumerate(NETWORKS):
            out.append('<text x="%d" y="%d" fill="%s">%d Gb/s</text>' % (
                x0 + pw - 60, y0 + 16 + 14 * j, colors[gbs], gbs))
    out.append('<text x="50" y="%d">Projected strong-scaling efficiency, '
               '1024 rays a step, alpha %g us, serial shares %g (fast), %g '
               '(reference): scripts/distributed-model.py</text>' % (
                   h - 8, args.alpha * 1e6, args.fast_serial,
                   args.reference_serial))
    out.append('</svg>')
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--svg", default=None)
    ap.add_argument("--fast-step", type=float, default=PLACEHOLDER_FAST_STEP)
    ap.add_argument("--reference-step", type=float,
                    default=PLACEHOLDER_REFERENCE_STEP)
    # Shares of one node's step that every node repeats whole: Adam over
    # the weights it updates and, for fast, the occupancy grid's refresh
    # (PLACEHOLDERS too: nerf-bench's breakdown measures both).
    ap.add_argument("--fast-serial", type=float, default=0.05)
    ap.add_argument("--reference-serial", type=float, default=0.005)
    ap.add_argument("--alpha", type=float, default=20e-6)
    args = ap.parse_args()
    if args.fast_step == PLACEHOLDER_FAST_STEP or \
            args.reference_step == PLACEHOLDER_REFERENCE_STEP:
        print("note: step times are PLACEHOLDERS; pass --fast-step and "
              "--reference-step from scripts/bench-mpi.sh", file=sys.stderr)
    rows = table(args)
    print("| preset | network | " +
          " | ".join("%d nodes" % p for p in NODES) + " |")
    print("|---|---|" + "---|" * len(NODES))
    for name, gbs, effs in rows:
        print("| %s | %d Gb/s | " % (name, gbs) +
              " | ".join("%.0f%%" % (100 * e) for e in effs) + " |")
    print()
    print("Exchange per step (one node's share of the traffic):")
    for gbs in NETWORKS:
        beta = 8 / (gbs * 1e9)
        for p in (2, 16, 64):
            print("  %3d Gb/s, %2d nodes: fast dense %.1f ms (ring) / "
                  "%.1f ms (rec. doubling), fast sparse %.1f ms, "
                  "reference %.1f ms" % (
                      gbs, p, 1e3 * ring(p, 4 * FAST_PARAMS, args.alpha, beta),
                      1e3 * recursive_doubling(p, 4 * FAST_PARAMS,
                                               args.alpha, beta),
                      1e3 * sparse(p, args.alpha, beta),
                      1e3 * allreduce(p, 4 * REFERENCE_PARAMS, args.alpha,
                                      beta)))
    if args.svg:
        write_svg(args.svg, rows, args)


if __name__ == "__main__":
    main()
