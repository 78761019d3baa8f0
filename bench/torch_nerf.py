#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""PyTorch peer of `nfield bench --nerf`: radiance-field training steps and a rendered view.

What it measures
----------------
The network, sampling, rendering and loss of configs/nerf_bunny.yaml as `nfield run` trains
it without the occupancy grid, written the way a plain PyTorch NeRF does it (float32, CPU):

    network   [x, d] -> gamma(x) (x and sin/cos at 2^l pi, l < 10: 63 wide)
              -> 4 x [Linear 128, ReLU] -> Linear 129 = [s, f]
              [f, gamma_d(d)] (d and sin/cos at 2^l pi, l < 4: 27 wide)
              -> Linear 64, ReLU -> Linear 3
              sigma = softplus(s), colour = sigmoid(raw); He-uniform weights, zero biases
    rays      --rays pixels per step drawn uniformly with replacement over all pixels of all
              training images, rays through the pixel centres (camera_angle_x, OpenGL axes),
              clipped to the box [-0.6, 0.6]^3 (rays missing it get the background only)
    samples   --samples stratified per ray, one uniform draw per bin of [near, far];
              delta_i = t_{i+1} - t_i, the last up to far
    render    alpha_i = 1 - exp(-sigma_i delta_i), T_i = exp(-sum_{j<i} sigma_j delta_j),
              C = sum T_i alpha_i c_i + T_n * white
    loss      mean over rays of |C - pixel|^2 (pixels composited on white), Adam (lr 5e-4)

A step is timed from drawing the rays to optimizer.zero_grad(); the median over --steps steps
after --warmup untimed ones gives rays/s. The view is the first test image, every pixel (or
every k-th of every k-th row, --render-stride), at the bin midpoints, evaluated under
torch.no_grad() in chunks of 65536 samples (NeRF's netchunk); median of --render-repeats.

How to run
----------
    /usr/bin/python3 bench/torch_nerf.py --data data/multiview/bunny_blender --threads 2
bench/compare_nerf.sh runs it next to `nfield bench --nerf` with OpenBLAS (OpenMP) in front.

Output: progress on stderr, one JSON line on stdout:
    {"impl": "torch", "bench": "nerf", "rays_per_s": ..., "median_step_ms": ...,
     "frame_ms": ..., "samples_per_step": ..., "threads": 2, "torch": "...", "blas": "..."}
"""

import argparse
import json
import math
import os
import statistics
import sys
import time

import numpy as np
from PIL import Image
import torch
from torch import nn
import torch.nn.functional as F

BOX = 0.6          # the scene box [-BOX, BOX]^3
POS_OCTAVES = 10
DIR_OCTAVES = 4
TRUNK = [128, 128, 128, 128]
COLOUR = [64]
NETCHUNK = 65536   # samples per forward call when rendering


def parse_args():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data", default=os.path.join(here, "..", "data", "multiview", "bunny_blender"),
                   help="folder with transforms_train.json and transforms_test.json")
    p.add_argument("--rays", type=int, default=1024, help="rays per step")
    p.add_argument("--samples", type=int, default=64, help="stratified samples per ray")
    p.add_argument("--steps", type=int, default=20, help="timed steps")
    p.add_argument("--warmup", type=int, default=3, help="untimed steps first")
    p.add_argument("--threads", type=int, default=2, help="torch.set_num_threads")
    p.add_argument("--lr", type=float, default=5e-4)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--render-stride", type=int, default=1,
                   help="render every k-th pixel of every k-th row of the test view")
    p.add_argument("--render-repeats", type=int, default=3, help="timed renders")
    return p.parse_args()


# --------------------------------------------------------------------------
# Data: transforms.json, PNGs composited on white, rays through pixel centres
# --------------------------------------------------------------------------
def load_views(json_path):
    """(origins, directions, rgb) of every pixel of every frame, each (frames, h*w, 3)."""
    with open(json_path) as fh:
        meta = json.load(fh)
    folder = os.path.dirname(json_path)
    origins, directions, colours = [], [], []
    for frame in meta["frames"]:
        path = os.path.join(folder, frame["file_path"])
        if not os.path.splitext(path)[1]:
            path += ".png"
        rgba = np.asarray(Image.open(path).convert("RGBA"), dtype=np.float32) / 255.0
        h, w = rgba.shape[:2]
        alpha = rgba[..., 3:4]
        colours.append((rgba[..., :3] * alpha + (1.0 - alpha)).reshape(-1, 3))
        focal = 0.5 * w / math.tan(0.5 * meta["camera_angle_x"])
        u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)  # pixel centres, row-major
        d_cam = np.stack([(u - 0.5 * w) / focal, -(v - 0.5 * h) / focal, -np.ones_like(u)], -1)
        c2w = np.asarray(frame["transform_matrix"], dtype=np.float64)
        d = d_cam.reshape(-1, 3) @ c2w[:3, :3].T
        directions.append(d / np.linalg.norm(d, axis=1, keepdims=True))
        origins.append(np.broadcast_to(c2w[:3, 3], d.shape))
    as_tensor = lambda a: torch.from_numpy(np.stack(a).astype(np.float32))
    return as_tensor(origins), as_tensor(directions), as_tensor(colours), (h, w)


def clip_to_box(o, d):
    """near, far of each ray inside [-BOX, BOX]^3 (slab test); near = far = 0 on a miss."""
    inv = 1.0 / d
    t0, t1 = (-BOX - o) * inv, (BOX - o) * inv
    near = torch.minimum(t0, t1).amax(-1).clamp(min=0.0)
    far = torch.maximum(t0, t1).amin(-1)
    hit = far > near
    return torch.where(hit, near, 0.0), torch.where(hit, far, 0.0), hit


def stratified(near, far, n, jitter):
    """t (R, n) and delta (R, n): one sample per bin of [near, far]."""
    u = torch.rand(near.shape[0], n) if jitter else torch.full((near.shape[0], n), 0.5)
    bin_ = ((far - near) / n)[:, None]
    t = near[:, None] + (torch.arange(n, dtype=torch.float32) + u) * bin_
    delta = torch.cat([t[:, 1:] - t[:, :-1], far[:, None] - t[:, -1:]], 1)
    return t, delta


# --------------------------------------------------------------------------
# Network
# --------------------------------------------------------------------------
def positional(x, octaves):
    """[x, sin(2^l pi x), cos(2^l pi x)] for l < octaves."""
    freq = math.pi * 2.0 ** torch.arange(octaves, dtype=torch.float32)
    z = (x[..., None, :] * freq[:, None]).flatten(-2)
    return torch.cat([x, torch.sin(z), torch.cos(z)], -1)


def dense(n_in, n_out):
    layer = nn.Linear(n_in, n_out)
    bound = math.sqrt(6.0 / n_in)  # He-uniform, as nfield's relu fields
    with torch.no_grad():
        layer.weight.uniform_(-bound, bound)
        layer.bias.zero_()
    return layer


class Radiance(nn.Module):
    def __init__(self):
        super().__init__()
        width, trunk = 3 * (1 + 2 * POS_OCTAVES), []
        for h in TRUNK:
            trunk += [dense(width, h), nn.ReLU()]
            width = h
        self.trunk = nn.Sequential(*trunk)
        self.head = dense(width, 1 + width)  # [s, f]
        width, colour = width + 3 * (1 + 2 * DIR_OCTAVES), []
        for c in COLOUR:
            colour += [dense(width, c), nn.ReLU()]
            width = c
        colour.append(dense(width, 3))
        self.colour = nn.Sequential(*colour)

    def forward(self, x, d):
        """sigma (N,) and colour (N, 3) at positions x and directions d (N, 3)."""
        sf = self.head(self.trunk(positional(x, POS_OCTAVES)))
        raw = self.colour(torch.cat([sf[:, 1:], positional(d, DIR_OCTAVES)], -1))
        return F.softplus(sf[:, 0]), torch.sigmoid(raw)


def render(net, o, d, near, far, hit, n, jitter):
    """Colour of each ray (R, 3) on white; rays that miss the box are white."""
    colour = torch.ones(o.shape[0], 3)
    o, d, near, far = o[hit], d[hit], near[hit], far[hit]
    t, delta = stratified(near, far, n, jitter)
    x = (o[:, None, :] + t[..., None] * d[:, None, :]).reshape(-1, 3)
    dirs = d[:, None, :].expand(-1, n, -1).reshape(-1, 3)
    if torch.is_grad_enabled():
        sigma, rgb = net(x, dirs)
    else:
        parts = [net(x[i:i + NETCHUNK], dirs[i:i + NETCHUNK]) for i in range(0, x.shape[0], NETCHUNK)]
        sigma, rgb = torch.cat([p[0] for p in parts]), torch.cat([p[1] for p in parts])
    tau = sigma.reshape(-1, n) * delta
    alpha = -torch.expm1(-tau)
    cum = torch.cumsum(tau, 1)
    trans = torch.exp(-torch.cat([torch.zeros_like(cum[:, :1]), cum[:, :-1]], 1))
    weights = trans * alpha
    c = (weights[..., None] * rgb.reshape(-1, n, 3)).sum(1) + torch.exp(-cum[:, -1:])
    colour = colour.index_put((hit.nonzero()[:, 0],), c)
    return colour, x.shape[0]


def blas_info():
    """The BLAS-like libraries mapped into this process."""
    libs = []
    with open("/proc/self/maps") as fh:
        for line in fh:
            parts = line.split()
            if len(parts) >= 6 and any(k in os.path.basename(parts[5]).lower()
                                       for k in ("blas", "mkl", "blis")):
                path = os.path.realpath(parts[5])
                if path not in libs:
                    libs.append(path)
    return ", ".join(libs) or "unknown"


def main():
    args = parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    load_before = os.getloadavg()[0]
    o_all, d_all, rgb_all, _ = load_views(os.path.join(args.data, "transforms_train.json"))
    o_all, d_all, rgb_all = o_all.reshape(-1, 3), d_all.reshape(-1, 3), rgb_all.reshape(-1, 3)
    net = Radiance()
    opt = torch.optim.Adam(net.parameters(), lr=args.lr, betas=(0.9, 0.999), eps=1e-8)

    times, samples = [], []
    for k in range(args.warmup + args.steps):
        start = time.perf_counter()
        pick = torch.randint(o_all.shape[0], (args.rays,))
        o, d, target = o_all[pick], d_all[pick], rgb_all[pick]
        near, far, hit = clip_to_box(o, d)
        colour, count = render(net, o, d, near, far, hit, args.samples, jitter=True)
        loss = ((colour - target) ** 2).sum(1).mean()
        loss.backward()
        opt.step()
        opt.zero_grad()
        if k >= args.warmup:
            times.append(1e3 * (time.perf_counter() - start))
            samples.append(count)
    print("step times (ms): " + " ".join(f"{t:.1f}" for t in times), file=sys.stderr)

    o_view, d_view, _, (h, w) = load_views(os.path.join(args.data, "transforms_test.json"))
    keep = torch.tensor([p for p in range(h * w)
                         if (p // w) % args.render_stride == 0 and (p % w) % args.render_stride == 0])
    frame_ms, frame_samples = [], 0
    with torch.no_grad():
        for _ in range(args.render_repeats):
            start = time.perf_counter()
            o, d = o_view[0][keep], d_view[0][keep]
            near, far, hit = clip_to_box(o, d)
            _, frame_samples = render(net, o, d, near, far, hit, args.samples, jitter=False)
            frame_ms.append(1e3 * (time.perf_counter() - start))
    median_ms = statistics.median(times)
    record = {"impl": "torch", "bench": "nerf", "rays_per_step": args.rays,
              "samples_per_step": round(statistics.mean(samples)), "steps": args.steps,
              "warmup": args.warmup, "threads": args.threads,
              "params": sum(p.numel() for p in net.parameters()),
              "rays_per_s": round(args.rays / (median_ms * 1e-3), 1),
              "median_step_ms": round(median_ms, 3), "final_loss": float(loss),
              "frame_ms": round(statistics.median(frame_ms), 2), "frame_pixels": int(keep.numel()),
              "frame_samples": frame_samples, "loadavg_1m_before": round(load_before, 2),
              "torch": torch.__version__, "blas": blas_info()}
    print(json.dumps(record), flush=True)


if __name__ == "__main__":
    main()
