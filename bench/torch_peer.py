#!/usr/bin/python3
"""A PyTorch peer of libnerf's training and rendering, timed as nerf-bench
times libnerf, and the two side by side.

The peer is the same method at the same sizes, written for this comparison:
the presets' networks (positional encoding with the raw input included, a
ReLU trunk whose skip layer takes the encoded position again, a sigma head,
a feature layer, one view layer and a sigmoid colour layer; a coarse and a
fine network), stratified coarse samples and inverse-CDF fine samples merged
with them for the fine network, alpha compositing onto white, the sum of the
two passes' mean squared errors, Adam with libnerf's defaults.  Rays and
target colours are random: the cost of a step does not depend on them.

    /usr/bin/python3 bench/torch_peer.py
        [--nerf-bench PATH | --nerf-json FILE] [--preset reference|tiny|all]
        [--seconds S] [--threads N] [--render-chunk R] [--nerf-args '...']
        [--json]

It first runs `nerf-bench --json` (found in the build folders unless given)
with the same preset, seconds and thread count, then times the peer, then
prints one table.  Benchmark only: the test suite never imports torch.
"""

import argparse
import glob
import json
import os
import subprocess
import sys
import time

import torch
import torch.nn.functional as F

# The presets as libnerf defines them (lib/model/model.c and the sampler's
# presets): trunk depth and width, the 0-based trunk layer whose input is
# [gamma(x), h], view branch width, and samples per ray.
PRESETS = {
    "reference": dict(depth=8, width=256, skip=5, view=128, coarse=64,
                      fine=128),
    "tiny": dict(depth=4, width=64, skip=2, view=32, coarse=32, fine=64),
}
POS_FREQS, DIR_FREQS = 10, 4
NEAR, FAR = 2.0, 6.0
BATCH_RAYS = 1024
MIN_TRAIN_STEPS = 2
LR0, LR1, DECAY_STEPS = 5e-4, 5e-5, 250000


def gamma(x, freqs):
    """[x, then per frequency 2^k: sin of the 3 coordinates, cos of them]."""
    scales = 2.0 ** torch.arange(freqs, dtype=x.dtype)
    angles = x.unsqueeze(-2) * scales.unsqueeze(-1)  # [..., freqs, 3]
    waves = torch.cat([torch.sin(angles), torch.cos(angles)], -1)
    return torch.cat([x, waves.flatten(-2)], -1)


class RadianceField(torch.nn.Module):
    def __init__(self, depth, width, skip, view):
        super().__init__()
        self.skip = skip
        pos_in = 3 + 6 * POS_FREQS
        dir_in = 3 + 6 * DIR_FREQS
        layers = []
        for i in range(depth):
            fan_in = pos_in if i == 0 else width
            if 0 < i == skip:
                fan_in += pos_in
            layers.append(torch.nn.Linear(fan_in, width))
        self.trunk = torch.nn.ModuleList(layers)
        self.to_sigma = torch.nn.Linear(width, 1)
        self.to_feature = torch.nn.Linear(width, width)
        self.view_layer = torch.nn.Linear(width + dir_in, view)
        self.to_rgb = torch.nn.Linear(view, 3)

    def forward(self, pos_code, dir_code):
        h = pos_code
        for i, layer in enumerate(self.trunk):
            if 0 < i == self.skip:
                h = torch.cat([pos_code, h], -1)
            h = F.relu(layer(h))
        sigma = self.to_sigma(h).squeeze(-1)
        v = F.relu(self.view_layer(torch.cat([self.to_feature(h), dir_code], -1)))
        return torch.sigmoid(self.to_rgb(v)), sigma


def stratified(n_rays, n, jitter):
    """Evenly spaced depths with both ends, each jittered inside the
    interval between its neighbours' midpoints when training."""
    t = torch.linspace(NEAR, FAR, n).expand(n_rays, n)
    if not jitter:
        return t.contiguous()
    mid = 0.5 * (t[:, 1:] + t[:, :-1])
    lo = torch.cat([t[:, :1], mid], 1)
    hi = torch.cat([mid, t[:, -1:]], 1)
    return lo + (hi - lo) * torch.rand(n_rays, n)


def importance(t, weights, n, random):
    """n depths drawn by inverse transform from the piecewise-constant
    density the inner weights (+1e-5) put on the midpoint intervals."""
    edges = 0.5 * (t[:, 1:] + t[:, :-1])            # [R, n_c - 1]
    w = weights[:, 1:-1] + 1e-5                      # [R, n_c - 2]
    cdf = torch.cumsum(w / w.sum(-1, keepdim=True), -1)
    cdf = torch.cat([torch.zeros_like(cdf[:, :1]), cdf], -1)
    if random:
        u = torch.rand(t.shape[0], n)
    else:
        u = torch.linspace(0.0, 1.0, n).expand(t.shape[0], n).contiguous()
    k = torch.searchsorted(cdf, u, right=True)
    last = cdf.shape[1] - 1
    i0 = (k - 1).clamp(0, last)
    i1 = k.clamp(0, last)
    c0, c1 = cdf.gather(1, i0), cdf.gather(1, i1)
    e0, e1 = edges.gather(1, i0), edges.gather(1, i1)
    span = c1 - c0
    span = torch.where(span < 1e-5, torch.ones_like(span), span)
    return e0 + (u - c0) / span * (e1 - e0)


def composite(rgb, sigma, t, dir_len):
    """Alpha compositing onto white; returns colours and weights."""
    gap = torch.cat([t[:, 1:] - t[:, :-1],
                     torch.full_like(t[:, :1], 1e10)], 1) * dir_len
    alpha = 1.0 - torch.exp(-F.relu(sigma) * gap)
    keep = torch.cumprod(torch.cat([torch.ones_like(alpha[:, :1]),
                                    1.0 - alpha + 1e-10], 1), 1)[:, :-1]
    w = alpha * keep
    colour = (w.unsqueeze(-1) * rgb).sum(1)
    return colour + (1.0 - w.sum(1, keepdim=True)), w


def run_network(net, origins, dirs, t):
    """The network on every sample o + t d of the rays."""
    n_rays, n = t.shape
    pts = origins.unsqueeze(1) + dirs.unsqueeze(1) * t.unsqueeze(-1)
    unit = dirs / dirs.norm(dim=-1, keepdim=True)
    rgb, sigma = net(gamma(pts.reshape(-1, 3), POS_FREQS),
                     gamma(unit.unsqueeze(1).expand(n_rays, n, 3)
                           .reshape(-1, 3), DIR_FREQS))
    return rgb.reshape(n_rays, n, 3), sigma.reshape(n_rays, n)


def render(nets, p, origins, dirs, training):
    dir_len = dirs.norm(dim=-1, keepdim=True)
    t_c = stratified(origins.shape[0], p["coarse"], training)
    rgb, sigma = run_network(nets[0], origins, dirs, t_c)
    colour_c, w = composite(rgb, sigma, t_c, dir_len)
    t_f = importance(t_c, w.detach(), p["fine"], training)
    t_all, _ = torch.sort(torch.cat([t_c, t_f.detach()], 1), 1)
    rgb, sigma = run_network(nets[1], origins, dirs, t_all)
    colour_f, _ = composite(rgb, sigma, t_all, dir_len)
    return colour_c, colour_f


def random_rays(n):
    """Rays from a sphere of radius 4 towards the origin, unnormalised
    directions of length about 1, as a camera at the Blender distance."""
    o = F.normalize(torch.randn(n, 3), dim=-1) * 4.0
    d = -o / 4.0 + 0.3 * (torch.rand(n, 3) - 0.5)
    return o, d


def time_training(nets, p, seconds, warmup):
    params = list(nets[0].parameters()) + list(nets[1].parameters())
    opt = torch.optim.Adam(params, lr=LR0, betas=(0.9, 0.999), eps=1e-7)

    def step(k):
        for g in opt.param_groups:
            g["lr"] = LR0 * (LR1 / LR0) ** (k / DECAY_STEPS)
        o, d = random_rays(BATCH_RAYS)
        target = torch.rand(BATCH_RAYS, 3)
        c, f = render(nets, p, o, d, True)
        loss = F.mse_loss(c, target) + F.mse_loss(f, target)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        return loss.item()

    for k in range(warmup):
        step(k)
    steps, t0, elapsed, loss = 0, time.perf_counter(), 0.0, float("nan")
    while elapsed < seconds or steps < MIN_TRAIN_STEPS:
        loss = step(warmup + steps)
        steps += 1
        elapsed = time.perf_counter() - t0
    return dict(train_rays_per_s=steps * BATCH_RAYS / elapsed,
                train_steps_timed=steps, train_seconds_timed=elapsed,
                train_last_loss=loss)


def time_render(nets, p, seconds, chunk):
    o, d = random_rays(chunk)
    with torch.no_grad():
        render(nets, p, o, d, False)  # warm-up
        rays, t0, elapsed = 0, time.perf_counter(), 0.0
        while elapsed < seconds or rays == 0:
            render(nets, p, o, d, False)
            rays += chunk
            elapsed = time.perf_counter() - t0
    return dict(render_rays_per_s=rays / elapsed, render_rays_timed=rays,
                render_seconds_timed=elapsed, render_chunk_rays=chunk)


def time_matmul(p, seconds):
    """torch's own rate on the widest trunk product of a training step
    (fine network, forward): what its BLAS gives at these shapes."""
    n, w = BATCH_RAYS * (p["coarse"] + p["fine"]), p["width"]
    x, wt = torch.rand(n, w), torch.rand(w, w)
    torch.mm(x, wt.t())
    reps, t0, elapsed = 0, time.perf_counter(), 0.0
    while elapsed < min(seconds, 2.0) or reps == 0:
        torch.mm(x, wt.t())
        reps += 1
        elapsed = time.perf_counter() - t0
    return 2.0 * n * w * w * reps / elapsed * 1e-9


def measure_torch(name, seconds, chunk):
    p = PRESETS[name]
    torch.manual_seed(0)
    nets = [RadianceField(p["depth"], p["width"], p["skip"], p["view"])
            for _ in range(2)]
    out = dict(preset=name)
    print(f"torch_peer: {name}: training...", file=sys.stderr, flush=True)
    out.update(time_training(nets, p, seconds, 3 if name == "tiny" else 1))
    print(f"torch_peer: {name}: rendering...", file=sys.stderr, flush=True)
    out.update(time_render(nets, p, seconds, chunk))
    out["matmul_gflops"] = time_matmul(p, seconds)
    out["params"] = sum(x.numel() for n in nets for x in n.parameters())
    return out


def find_nerf_bench(root):
    """The most recently built nerf-bench under the build folders."""
    found = [c for c in glob.glob(os.path.join(root, "build*", "bench",
                                               "nerf-bench"))
             + glob.glob(os.path.join(root, "build*", "*", "bench",
                                      "nerf-bench"))
             if os.access(c, os.X_OK)]
    return max(found, key=os.path.getmtime) if found else None


def build_type(exe):
    """The meson buildtype of the build folder holding exe, if known."""
    folder = os.path.dirname(os.path.dirname(os.path.abspath(exe)))
    try:
        with open(os.path.join(folder, "meson-info",
                               "intro-buildoptions.json")) as f:
            for o in json.load(f):
                if o["name"] == "buildtype":
                    return o["value"]
    except (OSError, ValueError, KeyError):
        pass
    return None


def ratio(a, b):
    return a / b if a and b else float("nan")


def print_table(nerf, peer, names, threads):
    print(f"threads: {threads} (torch.set_num_threads; nerf-bench --threads)")
    print(f"torch {torch.__version__}; nerf: {nerf.get('build_info', '?')}")
    print(f"BLAS: {nerf.get('blas_config')}")
    la = nerf.get("load_average_start")
    if la:
        print(f"load average at nerf-bench's start: {la[0]:.2f} {la[1]:.2f} "
              f"{la[2]:.2f}; at the peer's end: "
              f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print()
    head = f"{'preset':<10} {'figure':<30} {'libnerf':>12} {'torch':>12} " \
           f"{'libnerf/torch':>14}"
    print(head)
    print("-" * len(head))
    for name in names:
        n, t = nerf.get(name), peer.get(name)
        if not n or not t:
            continue
        tr_flops, re_flops = n["flops_per_train_ray"], n["flops_per_render_ray"]
        rows = [
            ("train rays/s", n["train_rays_per_s"], t["train_rays_per_s"],
             "{:,.0f}"),
            ("  GFLOP/s", n["train_rays_per_s"] * tr_flops * 1e-9,
             t["train_rays_per_s"] * tr_flops * 1e-9, "{:.1f}"),
            ("  share of sgemm bound", n["train_sgemm_share"] * 100,
             t["train_rays_per_s"] / n["train_sgemm_bound_rays_per_s"] * 100,
             "{:.1f}%"),
            ("render rays/s", n["render_rays_per_s"], t["render_rays_per_s"],
             "{:,.0f}"),
            ("  GFLOP/s", n["render_rays_per_s"] * re_flops * 1e-9,
             t["render_rays_per_s"] * re_flops * 1e-9, "{:.1f}"),
            ("  share of sgemm bound", n["render_sgemm_share"] * 100,
             t["render_rays_per_s"] / n["render_sgemm_bound_rays_per_s"] * 100,
             "{:.1f}%"),
            ("GEMM GFLOP/s (see notes)", n["sgemm_gflops"],
             t["matmul_gflops"], "{:.1f}"),
            ("parameters", n["network"]["params"], t["params"], "{:,}"),
        ]
        for label, a, b, fmt in rows:
            print(f"{name:<10} {label:<30} {fmt.format(a):>12} "
                  f"{fmt.format(b):>12} {ratio(a, b):>14.2f}")
        print()
    print("Notes: the sgemm bound is nerf-bench's (its cblas_sgemm rate on a "
          "training step's products\ndivided by the FLOPs per ray from the "
          "shapes). GEMM GFLOP/s: libnerf's figure is that\nsgemm rate; "
          "torch's is torch.mm on one trunk product of the fine network "
          "alone\n(1024 x 192 rows by 256 x 256 for the reference preset).\nThe peer's training steps draw random rays and colours; "
          "rendering runs no_grad chunks\nof --render-chunk rays.")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nerf-bench", help="path of the nerf-bench executable")
    ap.add_argument("--nerf-json", help="reuse this nerf-bench --json output "
                    "instead of running nerf-bench")
    ap.add_argument("--preset", choices=["reference", "tiny", "all"],
                    default="reference")
    ap.add_argument("--seconds", type=float, default=5.0,
                    help="time budget of each measurement (default 5)")
    ap.add_argument("--threads", type=int, default=os.cpu_count(),
                    help="threads for both (default: the cores)")
    ap.add_argument("--render-chunk", type=int, default=BATCH_RAYS,
                    help="rays per no_grad render call (default 1024)")
    ap.add_argument("--nerf-args", default="",
                    help="extra arguments for nerf-bench, e.g. '--no-800'")
    ap.add_argument("--json", action="store_true",
                    help="print {'nerf': ..., 'torch': ...} instead of the "
                    "table")
    args = ap.parse_args()
    names = ["reference", "tiny"] if args.preset == "all" else [args.preset]

    if args.nerf_json:
        with open(args.nerf_json) as f:
            nerf = json.load(f)
    else:
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        exe = args.nerf_bench or find_nerf_bench(root)
        if not exe:
            sys.exit("torch_peer: no nerf-bench found under build*/; build it "
                     "(bench/run.sh) or pass --nerf-bench PATH")
        bt = build_type(exe)
        print(f"torch_peer: running {exe} (buildtype {bt or 'unknown'})",
              file=sys.stderr, flush=True)
        if bt not in (None, "release"):
            print("torch_peer: warning: not a release build", file=sys.stderr)
        cmd = [exe, "--json", "--preset", args.preset, "--seconds",
               str(args.seconds), "--threads", str(args.threads)]
        cmd += args.nerf_args.split()
        done = subprocess.run(cmd, stdout=subprocess.PIPE, check=False)
        if done.returncode != 0:
            sys.exit(f"torch_peer: nerf-bench failed ({done.returncode})")
        nerf = json.loads(done.stdout)

    torch.set_num_threads(args.threads)
    peer = {name: measure_torch(name, args.seconds, args.render_chunk)
            for name in names}
    peer["threads"] = torch.get_num_threads()
    peer["torch_version"] = torch.__version__
    if args.json:
        print(json.dumps({"nerf": nerf, "torch": peer}, indent=1))
    else:
        print_table(nerf, peer, names, args.threads)


if __name__ == "__main__":
    main()
