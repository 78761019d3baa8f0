#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""DeepXDE's example Burgers restated in plain PyTorch: DeepXDE's figure on this machine
(DeepXDE itself cannot be installed here), for the table in docs/guide.md and docs/experiments.md.

    bench/deepxde_burgers_torch.py [ADAM_STEPS [LBFGS_ITERATIONS]] [--npz BURGERS_NPZ]

The reference is DeepXDE's test grid (examples/dataset/Burgers.npz: x 256 points in [-1, 1], t 100
in [0, 0.99]) with the Cole-Hopf solution computed here as solvers/problems/burgers_reference.h
does (trapezoidal rule in z, exponents shifted before exp); --npz also reads DeepXDE's file and
prints how far it lies from this one (2.9e-12 relative on the quiet machine). u_t + u u_x = (0.01/pi) u_xx on [-1, 1] x [0, 0.99], u(x, 0) =
-sin(pi x), u(+-1, t) = 0. As the example: a 3 x 20 tanh MLP (Glorot-normal weights, zero
biases), 2540 interior, 80 boundary and 160 initial points drawn once (the residual read at all
2780, as DeepXDE does), loss = mean r^2 + mean u^2 on the boundary + mean (u + sin pi x)^2 at
t = 0, Adam 1e-3 for 15,000 steps, then L-BFGS with DeepXDE's options (torch.optim.LBFGS: history
100, strong Wolfe line search, gradient tolerance 1e-8, no change tolerance, 15,000 iterations
in rounds of 1,000 as DeepXDE calls it, ending after a round of one iteration as DeepXDE does).
rel_l2 on the grid's 25,600 points. One thread, float32 as DeepXDE's default.
"""
import math
import sys
import time

import numpy as np
import torch

torch.set_num_threads(1)
torch.manual_seed(0)
np.random.seed(0)
args = sys.argv[1:]
npz = None
if "--npz" in args:
    at = args.index("--npz")
    npz = args[at + 1]
    del args[at:at + 2]
adam_steps = int(args[0]) if len(args) > 0 else 15000
lbfgs_iterations = int(args[1]) if len(args) > 1 else 15000
nu = 0.01 / math.pi


def cole_hopf(x, t, spacing=0.02):
    """u(x, t) of the benchmark, x and t arrays of one shape (burgers_reference.h)."""
    x, t = np.asarray(x, float).ravel(), np.asarray(t, float).ravel()
    half = math.ceil(math.sqrt(1 / (math.pi * nu) + 40) / spacing)
    z = spacing * np.arange(-half, half + 1)
    u = np.empty_like(x)
    for lo in range(0, x.size, 512):
        xs, ts = x[lo:lo + 512, None], t[lo:lo + 512, None]
        y = math.pi * (xs - np.sqrt(4 * nu * ts) * z[None, :])
        exponent = -z[None, :] ** 2 - np.cos(y) / (2 * math.pi * nu)
        w = np.exp(exponent - exponent.max(axis=1, keepdims=True))
        u[lo:lo + 512] = -(np.sin(y) * w).sum(axis=1) / w.sum(axis=1)
    return np.where(t == 0, -np.sin(math.pi * x), u)


data = {"x": np.linspace(-1, 1, 256)[:, None], "t": np.linspace(0, 0.99, 100)[:, None]}
grid_x, grid_t = np.meshgrid(data["x"].ravel(), data["t"].ravel(), indexing="ij")
data["usol"] = cole_hopf(grid_x, grid_t).reshape(256, 100)
if npz is not None:
    given = np.load(npz)
    difference = np.linalg.norm(given["usol"] - data["usol"]) / np.linalg.norm(given["usol"])
    print(f"{npz}: grid differs by {np.abs(given['x'] - data['x']).max():.1e} in x, "
          f"{np.abs(given['t'] - data['t']).max():.1e} in t; usol by {difference:.2e} relative")


def glorot(layer):
    torch.nn.init.xavier_normal_(layer.weight)
    torch.nn.init.zeros_(layer.bias)
    return layer


net = torch.nn.Sequential(glorot(torch.nn.Linear(2, 20)), torch.nn.Tanh(),
                          glorot(torch.nn.Linear(20, 20)), torch.nn.Tanh(),
                          glorot(torch.nn.Linear(20, 20)), torch.nn.Tanh(),
                          glorot(torch.nn.Linear(20, 1)))


def radical_inverse(i, base=2):
    r, q = 0.0, 1.0 / base
    while i:
        r += q * (i % base)
        i //= base
        q /= base
    return r


# DeepXDE's Hammersley points over the box, the boundary's times and the initial x evenly spread.
xi = torch.tensor([[-1 + 2 * (i + 1) / 2541, 0.99 * radical_inverse(i + 1)] for i in range(2540)])
tb = 0.99 * (torch.arange(80, dtype=torch.float32) + 0.5) / 80
xb = torch.stack([torch.where(torch.arange(80) % 2 == 0, -1.0, 1.0), tb], 1)
x0 = torch.stack([-1 + 2 * (torch.arange(160, dtype=torch.float32) + 0.5) / 160, torch.zeros(160)], 1)
xr = torch.cat([xb, x0, xi])
xx, tt = np.meshgrid(data["x"], data["t"])
probe = torch.tensor(np.vstack((xx.ravel(), tt.ravel())).T, dtype=torch.float32)
exact = torch.tensor(data["usol"].T.ravel(), dtype=torch.float32)


def loss_fn():
    x = xr.clone().requires_grad_(True)
    u = net(x)
    g = torch.autograd.grad(u.sum(), x, create_graph=True)[0]
    uxx = torch.autograd.grad(g[:, 0].sum(), x, create_graph=True)[0][:, 0]
    r = g[:, 1] + u[:, 0] * g[:, 0] - nu * uxx
    return ((r**2).mean() + (net(xb) ** 2).mean()
            + ((net(x0)[:, 0] + torch.sin(math.pi * x0[:, 0])) ** 2).mean())


def report(label, loss):
    with torch.no_grad():
        error = float((net(probe)[:, 0] - exact).norm() / exact.norm())
    print(label, float(loss), error, f"{time.time() - start:.1f}s", flush=True)
    return error


start, cpu0 = time.time(), time.process_time()
optimizer = torch.optim.Adam(net.parameters(), lr=1e-3)
for step in range(adam_steps):
    loss = loss_fn()
    if step % 1000 == 0:
        report(f"adam {step}", loss)
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
report(f"adam {adam_steps}", loss_fn())
lbfgs = torch.optim.LBFGS(net.parameters(), lr=1, max_iter=1000, max_eval=1250,
                          tolerance_grad=1e-8, tolerance_change=0, history_size=100,
                          line_search_fn="strong_wolfe")


def closure():
    lbfgs.zero_grad()
    loss = loss_fn()
    loss.backward()
    return loss


done = 0
while done < lbfgs_iterations:
    lbfgs.step(closure)
    taken = lbfgs.state[lbfgs._params[0]]["n_iter"]
    converged = taken - done <= 1               # DeepXDE's rule: a round of one iteration
    done = taken
    error = report(f"lbfgs {done}", loss_fn())
    if converged:
        break
error = report("final", loss_fn())
print(f"final rel_l2 {error:.4g} wall {time.time() - start:.1f} s cpu {time.process_time() - cpu0:.1f} s")
