#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""DeepXDE's example Helmholtz_Dirichlet_2d restated in plain PyTorch, for the study in
docs/experiments.md (2026-11-26): which point policy and boundary treatment let its network train.

    bench/deepxde_helmholtz_torch.py MODE STEPS [hard]

MODE: fixed (400 uniform points drawn once), resample (new points every step) or hammersley
(DeepXDE's default points, drawn once). `hard` multiplies the output by x(1-x)y(1-y) (the
example's hard_constraint = True) and drops the boundary loss. Prints step, loss, rel_l2 on a
64 x 64 grid and the elapsed time every 500 steps. One thread.
"""
import math
import sys
import time

import torch

torch.set_num_threads(1)
torch.manual_seed(0)
mode = sys.argv[1]
steps = int(sys.argv[2]) if len(sys.argv) > 2 else 5000
hard = len(sys.argv) > 3 and sys.argv[3] == "hard"
k0 = 4 * math.pi


def glorot(layer):
    torch.nn.init.xavier_uniform_(layer.weight)
    torch.nn.init.zeros_(layer.bias)
    return layer


layers = [glorot(torch.nn.Linear(2, 150)), glorot(torch.nn.Linear(150, 150)),
          glorot(torch.nn.Linear(150, 150)), glorot(torch.nn.Linear(150, 1))]
params = [p for layer in layers for p in layer.parameters()]


def field(x):
    h = x
    for layer in layers[:-1]:
        h = torch.sin(layer(h))
    out = layers[-1](h)
    if hard:
        out = out * (x[:, 0:1] * (1 - x[:, 0:1]) * x[:, 1:2] * (1 - x[:, 1:2]))
    return out


def interior(n):
    return torch.rand(n, 2)


def boundary(n):
    s = torch.rand(n)
    side = torch.randint(0, 4, (n,))
    x = torch.where(side == 0, 0 * s, torch.where(side == 1, 1 + 0 * s, s))
    y = torch.where(side == 2, 0 * s, torch.where(side == 3, 1 + 0 * s, s))
    return torch.stack([torch.where(side < 2, x, s), torch.where(side < 2, s, y)], 1)


def radical_inverse(i, base=2):
    r, q = 0.0, 1.0 / base
    while i:
        r += q * (i % base)
        i //= base
        q /= base
    return r


xi, xb = interior(400), boundary(80)
if mode == "hammersley":
    xi = torch.tensor([[(i + 0.5) / 400, radical_inverse(i + 1)] for i in range(400)])
    arc = torch.tensor([(i + 0.5) / 80 * 4 for i in range(80)])
    side, arc = (arc // 1).long(), arc % 1
    xb = torch.stack([
        torch.where(side == 0, arc, torch.where(side == 1, 1 + 0 * arc, torch.where(side == 2, 1 - arc, 0 * arc))),
        torch.where(side == 0, 0 * arc, torch.where(side == 1, arc, torch.where(side == 2, 1 + 0 * arc, 1 - arc)))], 1)

grid = torch.linspace(0, 1, 64)
gx, gy = torch.meshgrid(grid, grid, indexing="ij")
probe = torch.stack([gx.flatten(), gy.flatten()], 1)
exact = torch.sin(k0 * probe[:, 0]) * torch.sin(k0 * probe[:, 1])
optimizer = torch.optim.Adam(params, lr=1e-3)
start = time.time()
for step in range(steps + 1):
    if mode == "resample":
        xi, xb = interior(400), boundary(80)
    x = xi.clone().requires_grad_(True)
    u = field(x)
    g = torch.autograd.grad(u.sum(), x, create_graph=True)[0]
    uxx = torch.autograd.grad(g[:, 0].sum(), x, create_graph=True)[0][:, 0]
    uyy = torch.autograd.grad(g[:, 1].sum(), x, create_graph=True)[0][:, 1]
    r = -uxx - uyy - k0**2 * u[:, 0] - k0**2 * torch.sin(k0 * x[:, 0]) * torch.sin(k0 * x[:, 1])
    loss = (r**2).mean() + (0 if hard else 100 * (field(xb) ** 2).mean())
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
    if step % 500 == 0:
        with torch.no_grad():
            error = float((field(probe)[:, 0] - exact).norm() / exact.norm())
        print(step, float(loss), error, f"{time.time() - start:.1f}s", flush=True)
