#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""DeepXDE's example wave_1d restated in plain PyTorch: DeepXDE's figure on this machine
(DeepXDE itself cannot be installed here), for the table in docs/guide.md and docs/experiments.md.

    bench/deepxde_wave_torch.py [STEPS]

u_tt = 100 u_xx on [0, 1]^2 (C = 10, A = 2), u* = sin(pi x) cos(C pi t) + sin(A pi x) cos(A C pi t)
on the boundary and at t = 0, u_t(x, 0) = 0. As the example: DeepXDE's STMsFFN (layer sizes
[2, 100, 100, 100, 1], tanh, Glorot-uniform; frozen Fourier features N(0, 1) for x and N(0, 1),
N(0, 10^2) for t, 50 each; the inputs mapped by (x - 0.5) 2 sqrt(3); one shared MLP on each
feature set, the products of the x and t outputs into one linear layer), 360 interior, 360
boundary and 360 initial points, the residual read at all 1080 and its interior points drawn
anew every step (PDEPointResampler(period=1); uniform here, DeepXDE's randomly skipped
Hammersley), each loss term weighted by 5 / its initial value, Adam 1e-3 with inverse-time decay
(lr / (1 + 0.9 step / 2000)) for 10,000 steps. rel_l2 on a 100 x 100 grid. One thread, float32.
"""
import math
import sys
import time

import torch

torch.set_num_threads(1)
torch.manual_seed(0)
steps = int(sys.argv[1]) if len(sys.argv) > 1 else 10000
A, C = 2, 10


def exact_u(p):
    x, t = p[:, 0], p[:, 1]
    return torch.sin(math.pi * x) * torch.cos(C * math.pi * t) + torch.sin(A * math.pi * x) * torch.cos(A * C * math.pi * t)


def glorot(layer):
    torch.nn.init.xavier_uniform_(layer.weight)
    torch.nn.init.zeros_(layer.bias)
    return layer


bx = torch.randn(1, 50) * 1.0
bt = [torch.randn(1, 50) * 1.0, torch.randn(1, 50) * 10.0]
hidden = [glorot(torch.nn.Linear(100, 100)), glorot(torch.nn.Linear(100, 100))]
dense = glorot(torch.nn.Linear(200, 1))
params = [p for layer in hidden + [dense] for p in layer.parameters()]


def mlp(h):
    for layer in hidden:
        h = torch.tanh(layer(h))
    return h


def field(p):
    q = (p - 0.5) * 2 * math.sqrt(3)
    feature = lambda z, b: torch.cat([torch.cos(z @ b), torch.sin(z @ b)], 1)
    yx = mlp(feature(q[:, :1], bx))
    return dense(torch.cat([yx * mlp(feature(q[:, 1:], b)) for b in bt], 1))


def boundary(n):
    t = torch.rand(n)
    return torch.stack([torch.where(torch.rand(n) < 0.5, 0.0, 1.0), t], 1)


xb = boundary(360)
x0 = torch.stack([torch.rand(360), torch.zeros(360)], 1)
g = torch.linspace(0, 1, 100)
probe = torch.stack([a.flatten() for a in torch.meshgrid(g, g, indexing="ij")], 1)
exact = exact_u(probe)


def losses(xi):
    x = torch.cat([xb, x0, xi]).requires_grad_(True)
    u = field(x)
    d = torch.autograd.grad(u.sum(), x, create_graph=True)[0]
    uxx = torch.autograd.grad(d[:, 0].sum(), x, create_graph=True)[0][:, 0]
    utt = torch.autograd.grad(d[:, 1].sum(), x, create_graph=True)[0][:, 1]
    y0 = x0.clone().requires_grad_(True)
    u0 = field(y0)
    u0t = torch.autograd.grad(u0.sum(), y0, create_graph=True)[0][:, 1]
    return torch.stack([((utt - C**2 * uxx) ** 2).mean(), ((field(xb)[:, 0] - exact_u(xb)) ** 2).mean(),
                        ((u0[:, 0] - exact_u(x0)) ** 2).mean(), (u0t**2).mean()])


weights = 5 / losses(torch.rand(360, 2)).detach()
optimizer = torch.optim.Adam(params, lr=1e-3)
schedule = torch.optim.lr_scheduler.LambdaLR(optimizer, lambda k: 1 / (1 + 0.9 * k / 2000))
start, cpu0 = time.time(), time.process_time()
for step in range(steps + 1):
    loss = (weights * losses(torch.rand(360, 2))).sum()
    if step % 500 == 0 or step == steps:
        with torch.no_grad():
            error = float((field(probe)[:, 0] - exact).norm() / exact.norm())
        print(step, float(loss), error, f"{time.time() - start:.1f}s", flush=True)
    if step == steps:
        break
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
    schedule.step()
print(f"final rel_l2 {error:.4g} wall {time.time() - start:.1f} s cpu {time.process_time() - cpu0:.1f} s")
