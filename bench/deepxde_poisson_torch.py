#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""DeepXDE's example Poisson_Dirichlet_1d restated in plain PyTorch: DeepXDE's figure on this
machine (DeepXDE itself cannot be installed here), for the table in docs/guide.md and
docs/experiments.md.

    bench/deepxde_poisson_torch.py [STEPS]

-u'' = pi^2 sin(pi x) on [-1, 1], u(+-1) = sin(pi x) = 0, u* = sin(pi x). As the example: a
3 x 50 tanh MLP (Glorot-uniform weights, zero biases), 16 interior and 2 boundary points drawn
once (DeepXDE's 1-D Hammersley points are evenly spaced; the residual is also read at the
boundary points, as DeepXDE does), loss = mean r^2 + mean (u - g)^2 on the boundary, Adam 1e-3
for 10,000 steps. Prints step, loss, rel_l2 at 100 evenly spaced test points and the elapsed
time every 1000 steps. One thread.
"""
import math
import sys
import time

import torch

torch.set_num_threads(1)
torch.manual_seed(0)
torch.set_default_dtype(torch.float32)  # DeepXDE's default precision
steps = int(sys.argv[1]) if len(sys.argv) > 1 else 10000


def glorot(layer):
    torch.nn.init.xavier_uniform_(layer.weight)
    torch.nn.init.zeros_(layer.bias)
    return layer


net = torch.nn.Sequential(glorot(torch.nn.Linear(1, 50)), torch.nn.Tanh(),
                          glorot(torch.nn.Linear(50, 50)), torch.nn.Tanh(),
                          glorot(torch.nn.Linear(50, 50)), torch.nn.Tanh(),
                          glorot(torch.nn.Linear(50, 1)))
xb = torch.tensor([[-1.0], [1.0]])
xi = -1 + 2 * torch.arange(1, 17, dtype=torch.float32).unsqueeze(1) / 17
xr = torch.cat([xb, xi])                      # the residual's points: boundary and interior
probe = torch.linspace(-1, 1, 100).unsqueeze(1)
exact = torch.sin(math.pi * probe)
optimizer = torch.optim.Adam(net.parameters(), lr=1e-3)
start, cpu0 = time.time(), time.process_time()
for step in range(steps + 1):
    x = xr.clone().requires_grad_(True)
    u = net(x)
    ux = torch.autograd.grad(u.sum(), x, create_graph=True)[0]
    uxx = torch.autograd.grad(ux.sum(), x, create_graph=True)[0]
    r = -uxx - math.pi**2 * torch.sin(math.pi * x)
    loss = (r**2).mean() + ((net(xb) - torch.sin(math.pi * xb)) ** 2).mean()
    if step % 1000 == 0 or step == steps:
        with torch.no_grad():
            error = float((net(probe) - exact).norm() / exact.norm())
        print(step, float(loss), error, f"{time.time() - start:.1f}s", flush=True)
    if step == steps:
        break
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
print(f"final rel_l2 {error:.4g} wall {time.time() - start:.1f} s cpu {time.process_time() - cpu0:.1f} s")
