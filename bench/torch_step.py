#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""PyTorch peer benchmark for `nfield bench`: one full PINN training step.

What it measures
----------------
The wall-clock time of one training step of a physics-informed SIREN, done the
way the SIREN reference code (Sitzmann et al. 2020, `diff_operators.py`) does it:

    u = net(x)                                   # x: (N, d), requires_grad
    derivatives by torch.autograd.grad(..., create_graph=True)   # double backward
    loss = mean(residual**2)
    loss.backward(); Adam.step(); zero_grad()

Network (float32): d -> 256 -> 256 -> 256 -> 256 -> 1, sin(30 (W a + b)) on the
first and the three hidden layers, linear output layer (198,401 parameters for
d = 2).  Sitzmann initialization of the weights: first layer U(-1/n, 1/n), later
layers U(-sqrt(6/n)/30, sqrt(6/n)/30), n = fan-in; biases keep the nn.Linear
default U(-1/sqrt(n), 1/sqrt(n)), as in the reference code.

Operators (--op):
    laplacian   d = 2   r = u_xx + u_yy - f                  (Poisson)
    wave        d = 3   r = u_tt - c^2 (u_xx + u_yy), c = 1  (inputs x, y, t)
    biharmonic  d = 2   r = Laplace(Laplace(u)) - f          (four nested grads,
                        = u_xxxx + 2 u_xxyy + u_yyyy)
f is a fixed random tensor; the sample points are drawn before timing starts.

Only the training step is timed (median over --steps steps after --warmup
untimed ones).  peak_rss_mb is ru_maxrss of this process at the end, so run each
configuration in its own process.  It holds the interpreter's and libtorch's own
memory as well, so idle_rss_mb is ru_maxrss once torch is imported and the model,
the optimizer and the batches are made (before the first step), and
step_rss_increase_mb = peak_rss_mb - idle_rss_mb is what the training steps add:
the figure to set beside nfield's (bench/compare_torch.sh does).  The address space is capped (--mem-cap-gb,
default 20 GiB, via RLIMIT_AS) so that an over-large configuration fails with
{"error": "out of memory", ...} instead of taking the machine down.

How to run
----------
    /usr/bin/python3 bench/torch_step.py --op laplacian --batch 4096
    /usr/bin/python3 bench/torch_step.py --selftest
To make sure OpenBLAS (OpenMP build) serves torch's BLAS calls:
    LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/openblas-openmp OMP_NUM_THREADS=2 \
        /usr/bin/python3 bench/torch_step.py --op wave --batch 1024
bench/compare_torch.sh runs all configurations next to `nfield bench`.

Output: one JSON line on stdout (diagnostics go to stderr), e.g.
    {"impl": "torch", "op": "laplacian", "dims": 2, "batch": 4096,
     "median_step_ms": ..., "peak_rss_mb": ..., "idle_rss_mb": ...,
     "step_rss_increase_mb": ..., "threads": 2, "torch": "...",
     "blas": "..."}
"""

import argparse
import ctypes
import json
import math
import os
import resource
import statistics
import sys
import time

OPS = {"laplacian": 2, "wave": 3, "biharmonic": 2}  # operator -> input dimension
OMEGA0 = 30.0
WIDTH = 256
HIDDEN_LAYERS = 3
WAVE_C = 1.0


def cap_address_space(gib):
    """Limit this process's virtual address space to `gib` GiB (RLIMIT_AS).

    Done before torch is imported so that every allocation (torch, OpenBLAS
    buffers, thread stacks) counts.  A failing allocation then raises inside
    torch ("DefaultCPUAllocator: can't allocate memory") and we can report it.
    """
    if gib <= 0:
        return
    limit = int(gib * (1 << 30))
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY and hard < limit:
        limit = hard
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--op", choices=sorted(OPS), default="laplacian")
    p.add_argument("--batch", type=int, default=1024, help="points per step (N)")
    p.add_argument("--steps", type=int, default=20, help="timed steps")
    p.add_argument("--warmup", type=int, default=3, help="untimed steps before timing")
    p.add_argument("--threads", type=int, default=2, help="torch.set_num_threads")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--mem-cap-gb", type=float, default=20.0,
                   help="RLIMIT_AS cap in GiB (0 = none)")
    p.add_argument("--selftest", action="store_true",
                   help="check the operators on analytic functions and exit")
    return p.parse_args()


ARGS = parse_args()
cap_address_space(ARGS.mem_cap_gb)

import torch  # noqa: E402  (imported after the address-space cap on purpose)
from torch import nn  # noqa: E402


# --------------------------------------------------------------------------
# SIREN
# --------------------------------------------------------------------------
class SineLayer(nn.Module):
    """y = sin(omega0 * (W a + b)) with Sitzmann initialization."""

    def __init__(self, n_in, n_out, is_first):
        super().__init__()
        self.linear = nn.Linear(n_in, n_out)
        bound = 1.0 / n_in if is_first else math.sqrt(6.0 / n_in) / OMEGA0
        with torch.no_grad():
            self.linear.weight.uniform_(-bound, bound)

    def forward(self, a):
        return torch.sin(OMEGA0 * self.linear(a))


class Siren(nn.Module):
    def __init__(self, dims, width=WIDTH, hidden_layers=HIDDEN_LAYERS):
        super().__init__()
        layers = [SineLayer(dims, width, is_first=True)]
        layers += [SineLayer(width, width, is_first=False) for _ in range(hidden_layers)]
        out = nn.Linear(width, 1)  # linear output layer, SIREN init
        bound = math.sqrt(6.0 / width) / OMEGA0
        with torch.no_grad():
            out.weight.uniform_(-bound, bound)
        layers.append(out)
        self.net = nn.Sequential(*layers)

    def forward(self, x):
        return self.net(x)


# --------------------------------------------------------------------------
# Differential operators, as in SIREN's diff_operators.py (reverse over reverse)
# --------------------------------------------------------------------------
def gradient(y, x):
    """dy/dx for y of shape (N, 1): returns (N, d), keeping the graph."""
    return torch.autograd.grad(y, [x], grad_outputs=torch.ones_like(y),
                               create_graph=True)[0]


def second_derivatives(u, x, axes):
    """[d²u/dx_i² for i in axes], each (N, 1): one backward through grad u per axis."""
    g = gradient(u, x)
    out = []
    for i in axes:
        gi = g[:, i:i + 1]
        out.append(torch.autograd.grad(gi, [x], grad_outputs=torch.ones_like(gi),
                                       create_graph=True)[0][:, i:i + 1])
    return out


def laplace(u, x, axes=None):
    """Sum of d²u/dx_i² over `axes` (all input axes by default)."""
    if axes is None:
        axes = range(x.shape[1])
    terms = second_derivatives(u, x, axes)
    lap = terms[0]
    for t in terms[1:]:
        lap = lap + t
    return lap


def operator(op, u, x):
    """The differential operator of `op` applied to u(x), shape (N, 1)."""
    if op == "laplacian":
        return laplace(u, x)
    if op == "wave":  # inputs (x, y, t)
        u_xx, u_yy, u_tt = second_derivatives(u, x, (0, 1, 2))
        return u_tt - WAVE_C ** 2 * (u_xx + u_yy)
    if op == "biharmonic":  # four nested autograd.grad levels
        return laplace(laplace(u, x), x)
    raise ValueError(op)


# --------------------------------------------------------------------------
# Self-test: operators against analytic functions, and on the SIREN itself
# against finite differences (float64)
# --------------------------------------------------------------------------
def selftest():
    torch.manual_seed(1)
    ok = True

    def check(name, got, want, tol):
        nonlocal ok
        err = (got - want).abs().max().item()
        scale = max(want.abs().max().item(), 1.0)
        passed = err <= tol * scale
        ok &= passed
        print(f"  {'ok  ' if passed else 'FAIL'} {name}: max |err| = {err:.3e} "
              f"(scale {scale:.3e}, tol {tol:g})", file=sys.stderr)

    def pts(d, n=64):
        return (torch.rand(n, d, dtype=torch.float64) * 4 - 2).requires_grad_(True)

    # Laplacian of u = sin(x) sin(2y) is -5u.
    x = pts(2)
    u = (torch.sin(x[:, 0]) * torch.sin(2 * x[:, 1])).unsqueeze(1)
    check("laplacian sin(x)sin(2y) = -5u", operator("laplacian", u, x), -5 * u, 1e-12)

    # Wave: u = sin(x) sin(2y) cos(3t): u_tt = -9u, u_xx + u_yy = -5u -> -4u (c = 1).
    x = pts(3)
    u = (torch.sin(x[:, 0]) * torch.sin(2 * x[:, 1]) * torch.cos(3 * x[:, 2])).unsqueeze(1)
    check("wave sin(x)sin(2y)cos(3t) = -4u", operator("wave", u, x), -4 * u, 1e-12)
    # ... and a travelling wave sin(x + t) is an exact solution: residual 0.
    u = torch.sin(x[:, 0] + x[:, 2]).unsqueeze(1)
    check("wave sin(x+t) = 0", operator("wave", u, x), torch.zeros_like(u), 1e-12)

    # Biharmonic: sin(x) sin(2y) -> 25u;  x^2 y^2 -> 2 u_xxyy = 8;  x^4 + y^4 -> 48.
    x = pts(2)
    u = (torch.sin(x[:, 0]) * torch.sin(2 * x[:, 1])).unsqueeze(1)
    check("biharmonic sin(x)sin(2y) = 25u", operator("biharmonic", u, x), 25 * u, 1e-11)
    u = (x[:, 0] ** 2 * x[:, 1] ** 2).unsqueeze(1)
    check("biharmonic x^2 y^2 = 8", operator("biharmonic", u, x),
          torch.full_like(u, 8.0), 1e-12)
    u = (x[:, 0] ** 4 + x[:, 1] ** 4).unsqueeze(1)
    check("biharmonic x^4 + y^4 = 48", operator("biharmonic", u, x),
          torch.full_like(u, 48.0), 1e-12)

    # The network itself: parameter count and operators against central differences.
    net = Siren(2)
    n_params = sum(p.numel() for p in net.parameters())
    ok &= n_params == 198401
    print(f"  {'ok  ' if n_params == 198401 else 'FAIL'} SIREN d=2 has {n_params} "
          f"parameters (expected 198401)", file=sys.stderr)
    net = net.double()
    with torch.no_grad():
        x0 = torch.rand(16, 2, dtype=torch.float64) * 2 - 1
        h = 1e-3
        fd = torch.zeros(16, 1, dtype=torch.float64)
        for i in range(2):
            e = torch.zeros(2, dtype=torch.float64)
            e[i] = h
            fd += (net(x0 + e) - 2 * net(x0) + net(x0 - e)) / h ** 2
    x = x0.clone().requires_grad_(True)
    check("SIREN laplacian vs central differences", operator("laplacian", net(x), x), fd, 1e-3)
    # Wave on a d = 3 SIREN against central differences.
    net3 = Siren(3).double()
    with torch.no_grad():
        x0 = torch.rand(16, 3, dtype=torch.float64) * 2 - 1
        fd = torch.zeros(16, 1, dtype=torch.float64)
        for i, w in ((0, -1.0), (1, -1.0), (2, 1.0)):
            e = torch.zeros(3, dtype=torch.float64)
            e[i] = h
            fd += w * (net3(x0 + e) - 2 * net3(x0) + net3(x0 - e)) / h ** 2
    x = x0.clone().requires_grad_(True)
    check("SIREN wave vs central differences", operator("wave", net3(x), x), fd, 1e-3)
    # Biharmonic on the d = 2 SIREN: central differences of its autograd Laplacian.
    def lap_net(p):
        p = p.clone().requires_grad_(True)
        return laplace(net(p), p).detach()
    x0 = torch.rand(16, 2, dtype=torch.float64) * 2 - 1
    fd = torch.zeros(16, 1, dtype=torch.float64)
    for i in range(2):
        e = torch.zeros(2, dtype=torch.float64)
        e[i] = h
        fd += (lap_net(x0 + e) - 2 * lap_net(x0) + lap_net(x0 - e)) / h ** 2
    x = x0.clone().requires_grad_(True)
    check("SIREN biharmonic vs differences of its Laplacian",
          operator("biharmonic", net(x), x), fd, 1e-3)

    print("selftest " + ("passed" if ok else "FAILED"), file=sys.stderr)
    return ok


# --------------------------------------------------------------------------
# Which BLAS serves torch's sgemm
# --------------------------------------------------------------------------
def blas_info():
    """Describe the BLAS library torch's sgemm_ calls resolve to.

    Looks up `sgemm_` from libtorch_cpu's dependency scope and asks dladdr which
    file it lives in; falls back on the BLAS-like libraries mapped in
    /proc/self/maps.  Adds openblas_get_config() when that library is OpenBLAS.
    """
    mapped = []
    try:
        with open("/proc/self/maps") as fh:
            for line in fh:
                parts = line.split()
                if len(parts) >= 6:
                    base = os.path.basename(parts[5]).lower()
                    if any(k in base for k in ("blas", "mkl", "atlas", "blis", "lapack")):
                        if parts[5] not in mapped:
                            mapped.append(parts[5])
    except OSError:
        pass

    provider = None
    try:
        torch_lib = os.path.join(os.path.dirname(torch.__file__), "lib", "libtorch_cpu.so")
        lib = ctypes.CDLL(torch_lib if os.path.exists(torch_lib) else None)
        addr = ctypes.cast(lib.sgemm_, ctypes.c_void_p).value

        class DlInfo(ctypes.Structure):
            _fields_ = [("dli_fname", ctypes.c_char_p), ("dli_fbase", ctypes.c_void_p),
                        ("dli_sname", ctypes.c_char_p), ("dli_saddr", ctypes.c_void_p)]

        info = DlInfo()
        if ctypes.CDLL(None).dladdr(ctypes.c_void_p(addr), ctypes.byref(info)):
            provider = os.path.realpath(info.dli_fname.decode())
    except (OSError, AttributeError):
        pass

    if provider is None:
        provider = next((os.path.realpath(m) for m in mapped if "libblas" in m),
                        mapped[0] if mapped else "unknown")
    desc = provider
    try:
        cfg_lib = ctypes.CDLL(provider)
        cfg_lib.openblas_get_config.restype = ctypes.c_char_p
        desc += " [" + cfg_lib.openblas_get_config().decode().strip()
        desc += f"; threads={cfg_lib.openblas_get_num_threads()}]"
    except (OSError, AttributeError):
        pass
    return desc


# --------------------------------------------------------------------------
# Benchmark
# --------------------------------------------------------------------------
def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


IDLE_RSS_MB = None  # ru_maxrss before the first step (set by run_benchmark)


def run_benchmark(args):
    global IDLE_RSS_MB
    d = OPS[args.op]
    torch.manual_seed(args.seed)
    net = Siren(d)
    opt = torch.optim.Adam(net.parameters(), lr=1e-4)

    # Everything random is drawn before timing: one batch of points per step
    # and a fixed right-hand side f.
    n_total = args.warmup + args.steps
    batches = [(torch.rand(args.batch, d) * 2 - 1).requires_grad_(True)
               for _ in range(n_total)]
    f = torch.randn(args.batch, 1)
    IDLE_RSS_MB = peak_rss_mb()

    def step(x):
        u = net(x)
        lu = operator(args.op, u, x)
        r = lu if args.op == "wave" else lu - f
        loss = (r * r).mean()
        loss.backward()
        opt.step()
        opt.zero_grad()
        return loss

    times = []
    for k, x in enumerate(batches):
        t0 = time.perf_counter()
        loss = step(x)
        t1 = time.perf_counter()
        if k >= args.warmup:
            times.append((t1 - t0) * 1e3)
        if not torch.isfinite(loss):
            print(f"warning: non-finite loss at step {k}", file=sys.stderr)
    print(f"step times (ms): {' '.join(f'{t:.1f}' for t in times)}", file=sys.stderr)
    return times, sum(p.numel() for p in net.parameters())


def main():
    if ARGS.selftest:
        sys.exit(0 if selftest() else 1)

    torch.set_num_threads(ARGS.threads)
    record = {"impl": "torch", "op": ARGS.op, "dims": OPS[ARGS.op], "batch": ARGS.batch}
    # Other work on the machine distorts the timings (OpenMP threads spin and
    # get descheduled); the 1-minute load average before the run flags that.
    load_before = os.getloadavg()[0]
    try:
        times, n_params = run_benchmark(ARGS)
        record.update(median_step_ms=round(statistics.median(times), 3),
                      min_step_ms=round(min(times), 3))
        rc = 0
    except (RuntimeError, MemoryError) as exc:
        msg = str(exc)
        if isinstance(exc, MemoryError) or "alloc" in msg.lower() or "memory" in msg.lower():
            record.update(error="out of memory", mem_cap_gb=ARGS.mem_cap_gb)
            print(f"out of memory: {msg.splitlines()[0] if msg else type(exc).__name__}",
                  file=sys.stderr)
            rc = 3
        else:
            raise
        n_params = None
    peak = peak_rss_mb()
    record.update(peak_rss_mb=round(peak, 1))
    if IDLE_RSS_MB is not None:
        record.update(idle_rss_mb=round(IDLE_RSS_MB, 1), step_rss_increase_mb=round(peak - IDLE_RSS_MB, 1))
    record.update(threads=ARGS.threads,
                  steps=ARGS.steps, warmup=ARGS.warmup, params=n_params,
                  loadavg_1m_before=round(load_before, 2),
                  torch=torch.__version__, blas=blas_info())
    print(json.dumps(record), flush=True)
    sys.exit(rc)


if __name__ == "__main__":
    main()
