#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Steady lid-driven cavity at Re = 100 by finite differences, to check the Ghia table.

The stream function–vorticity form on the unit square (u = ψ_y, v = −ψ_x, ω = v_x − u_y),

    −Δψ = ω,    ψ_y ω_x − ψ_x ω_y = ν Δω,    ν = 1/Re,

with ψ = 0 on the walls and Thom's wall vorticity (ψ = 0 and ψ_n given on the wall:
ω_w = −2 ψ_1/h² on the fixed walls, −2 ψ_1/h² − 2U/h under the lid, ψ_1 the first node
inside), second-order central differences on an (N+1)² grid, solved by Newton's method
with the sparse Jacobian (from the Stokes flow, by continuation in Re). The centreline
velocities come from ψ by fourth-order differences, interpolated to Ghia's points with a
cubic spline.

Prints the largest difference between Ghia's tables (data/ghia_re100_u_centreline.csv,
_v_centreline.csv) and
this solution on each grid, and between the two finest grids (the solution's own error):

    scripts/cavity_reference.py [N ...]     # default 128 256
    PYTHONPATH=build/python scripts/cavity_reference.py 64 128 --run out/lid_driven_cavity/checkpoint.h5 ...

With --run, each checkpoint of configs/lid_driven_cavity.yaml (nfield's Python module loads
it; u = w + U and v = s + V with the lift of scripts/cavity_lift.py) is compared at Ghia's
points with Ghia and with the Richardson extrapolation (4 f_2n − f_n)/3 of the two finest grids.
"""
import pathlib
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.interpolate import CubicSpline

ROOT = pathlib.Path(__file__).resolve().parent.parent


def read_table(name, along, value):
    """The (along, value) pairs of one of Ghia's tables (data/ghia_re100_*_centreline.csv)."""
    lines = [l for l in open(ROOT / "data" / name, encoding="utf-8") if l.strip() and not l.startswith("#")]
    header = [s.strip() for s in lines[0].split(",")]
    rows = [dict(zip(header, map(float, l.split(",")))) for l in lines[1:]]
    return np.array([(r[along], r[value]) for r in rows])


def read_ghia():
    """(y, u) along x = 0.5 and (x, v) along y = 0.5 from the data files."""
    return read_table("ghia_re100_u_centreline.csv", "y", "u"), read_table("ghia_re100_v_centreline.csv", "x", "v")


def solve(n, re, lid=1.0):
    """ψ on the (n+1)² grid (index [i, j] = (x_i, y_j)) of the steady flow at Reynolds re."""
    h = 1.0 / n
    m = n + 1
    idx = np.arange(m * m).reshape(m, m)
    npsi = m * m
    inner = np.zeros((m, m), bool)
    inner[1:-1, 1:-1] = True
    ii, jj = np.nonzero(inner)

    def residual_and_jacobian(z, nu):
        psi = z[:npsi].reshape(m, m)
        om = z[npsi:].reshape(m, m)
        rows, cols, vals = [], [], []
        F = np.zeros(2 * npsi)

        def add(r, c, v):
            rows.append(np.broadcast_to(r, np.shape(v)).ravel())
            cols.append(np.broadcast_to(c, np.shape(v)).ravel())
            vals.append(np.asarray(v, float).ravel())

        # Walls: ψ = 0; Thom's vorticity; corners ω = 0 (no interior stencil reads them).
        wall = ~inner
        bi, bj = np.nonzero(wall)
        F[idx[bi, bj]] = psi[bi, bj]
        add(idx[bi, bj], idx[bi, bj], np.ones(len(bi)))
        for i, j in zip(bi, bj):
            r = npsi + idx[i, j]
            corner = (i in (0, n)) and (j in (0, n))
            if corner:
                F[r] = om[i, j]
                add(r, npsi + idx[i, j], 1.0)
                continue
            if j == 0:
                a, b, extra = i, 1, 0.0
            elif j == n:
                a, b, extra = i, n - 1, -2.0 * lid / h
            elif i == 0:
                a, b, extra = 1, j, 0.0
            else:
                a, b, extra = n - 1, j, 0.0
            F[r] = om[i, j] + 2.0 * psi[a, b] / h**2 - extra
            add(r, npsi + idx[i, j], 1.0)
            add(r, idx[a, b], 2.0 / h**2)
        c, e, w, nn, s = idx[ii, jj], idx[ii + 1, jj], idx[ii - 1, jj], idx[ii, jj + 1], idx[ii, jj - 1]
        lap_psi = (psi[ii + 1, jj] + psi[ii - 1, jj] + psi[ii, jj + 1] + psi[ii, jj - 1] - 4 * psi[ii, jj]) / h**2
        lap_om = (om[ii + 1, jj] + om[ii - 1, jj] + om[ii, jj + 1] + om[ii, jj - 1] - 4 * om[ii, jj]) / h**2
        # −Δψ − ω = 0
        F[c] = -lap_psi - om[ii, jj]
        for k, wgt in ((c, 4 / h**2), (e, -1 / h**2), (w, -1 / h**2), (nn, -1 / h**2), (s, -1 / h**2)):
            add(c, k, np.full(len(c), wgt))
        add(c, npsi + c, -np.ones(len(c)))
        # ψ_y ω_x − ψ_x ω_y − ν Δω = 0
        px = (psi[ii + 1, jj] - psi[ii - 1, jj]) / (2 * h)
        py = (psi[ii, jj + 1] - psi[ii, jj - 1]) / (2 * h)
        ox = (om[ii + 1, jj] - om[ii - 1, jj]) / (2 * h)
        oy = (om[ii, jj + 1] - om[ii, jj - 1]) / (2 * h)
        r = npsi + c
        F[r] = py * ox - px * oy - nu * lap_om
        add(r, npsi + c, np.full(len(c), 4 * nu / h**2))
        for k in (e, w, nn, s):
            add(r, npsi + k, np.full(len(c), -nu / h**2))
        add(r, npsi + e, py / (2 * h))
        add(r, npsi + w, -py / (2 * h))
        add(r, npsi + nn, -px / (2 * h))
        add(r, npsi + s, px / (2 * h))
        add(r, nn, ox / (2 * h))
        add(r, s, -ox / (2 * h))
        add(r, e, -oy / (2 * h))
        add(r, w, oy / (2 * h))
        J = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(2 * npsi, 2 * npsi))
        return F, J

    z = np.zeros(2 * npsi)
    for r in sorted({min(re, 10.0), min(re, 40.0), re}):
        for it in range(30):
            F, J = residual_and_jacobian(z, 1.0 / r)
            dz = spla.spsolve(J, -F)
            z += dz
            if np.max(np.abs(dz)) < 1e-11 * max(1.0, np.max(np.abs(z))):
                break
        print(f"  n={n} Re={r:g}: Newton {it + 1} steps, |F| {np.max(np.abs(residual_and_jacobian(z, 1 / r)[0])):.1e}",
              flush=True)
    return z[:npsi].reshape(m, m)


def centrelines(psi):
    """u(0.5, y) and v(x, 0.5) on the grid, by fourth-order differences of ψ (second order
    next to the walls; the wall values are the boundary data)."""
    n = psi.shape[0] - 1
    h = 1.0 / n
    mid = n // 2

    def d(line):
        g = np.zeros_like(line)
        g[2:-2] = (line[:-4] - 8 * line[1:-3] + 8 * line[3:-1] - line[4:]) / (12 * h)
        g[1] = (line[2] - line[0]) / (2 * h)
        g[-2] = (line[-1] - line[-3]) / (2 * h)
        return g

    u = d(psi[mid, :])
    u[0], u[-1] = 0.0, 1.0
    v = -d(psi[:, mid])
    v[0], v[-1] = 0.0, 0.0
    s = np.linspace(0, 1, n + 1)
    return CubicSpline(s, u), CubicSpline(s, v)


def network_centrelines(checkpoint, ghia_u, ghia_v):
    """u at Ghia's points on x = 0.5 and v on y = 0.5 from a lid_driven_cavity checkpoint."""
    import nfield
    from cavity_lift import lift
    points = np.concatenate([np.column_stack([np.full(len(ghia_u), 0.5), ghia_u[:, 0]]),
                             np.column_stack([ghia_v[:, 0], np.full(len(ghia_v), 0.5)])])
    wsp = np.asarray(nfield.load(checkpoint).values(points))
    d = 4 / (4 - np.pi ** 2)
    env = dict(A=-d * np.pi ** 2 / 4, C=d * np.pi / 2, D=d, nu=0.01, pi=np.pi, sin=np.sin, cos=np.cos,
               atan2=np.arctan2, x=points[:, 0], y=points[:, 1])
    texts = lift()
    u = wsp[:, 0] + eval(texts["U"].replace("^", "**"), env)
    v = wsp[:, 1] + eval(texts["V"].replace("^", "**"), env)
    return u[:len(ghia_u)], v[len(ghia_u):]


def compare_runs(checkpoints, found, ghia_u, ghia_v):
    (_, u1, v1), (_, u2, v2) = found[-2], found[-1]
    fine_u = (4 * u2(ghia_u[:, 0]) - u1(ghia_u[:, 0])) / 3
    fine_v = (4 * v2(ghia_v[:, 0]) - v1(ghia_v[:, 0])) / 3
    print(f"extrapolated FD − Ghia: max |Δu| {np.abs(fine_u - ghia_u[:, 1]).max():.2e}, "
          f"max |Δv| {np.abs(fine_v - ghia_v[:, 1]).max():.2e}")
    for checkpoint in checkpoints:
        u, v = network_centrelines(checkpoint, ghia_u, ghia_v)
        print(f"{checkpoint}: against Ghia max |Δu| {np.abs(u - ghia_u[:, 1]).max():.2e}, "
              f"max |Δv| {np.abs(v - ghia_v[:, 1]).max():.2e}; against the extrapolated FD "
              f"max |Δu| {np.abs(u - fine_u).max():.2e}, max |Δv| {np.abs(v - fine_v).max():.2e}")


def main():
    import argparse
    parser = argparse.ArgumentParser(description="The lid-driven cavity at Re = 100 by finite differences.")
    parser.add_argument("sizes", type=int, nargs="*", default=[128, 256], help="grid cells per side (default 128 256)")
    parser.add_argument("--run", nargs="+", default=[], metavar="CHECKPOINT",
                        help="checkpoint.h5 files of configs/lid_driven_cavity.yaml runs to compare")
    args = parser.parse_args()
    sizes, checkpoints = args.sizes, args.run
    if any(n < 8 or n % 2 for n in sizes):
        parser.error(f"grid sizes must be even and at least 8, got {sizes}")
    if checkpoints and (len(sizes) < 2 or sizes[-1] != 2 * sizes[-2]):
        parser.error(f"--run extrapolates from the last two grid sizes, which must be n and 2n, got {sizes}")
    for checkpoint in checkpoints:
        if not pathlib.Path(checkpoint).is_file():
            parser.error(f"--run: no such checkpoint file: {checkpoint}")
    ghia_u, ghia_v = read_ghia()
    found = []
    for n in sizes:
        u, v = centrelines(solve(n, 100.0))
        du = np.abs(u(ghia_u[:, 0]) - ghia_u[:, 1])
        dv = np.abs(v(ghia_v[:, 0]) - ghia_v[:, 1])
        print(f"n={n}: Ghia − FD: max |Δu| {du.max():.2e} at y={ghia_u[du.argmax(), 0]}, "
              f"max |Δv| {dv.max():.2e} at x={ghia_v[dv.argmax(), 0]}", flush=True)
        found.append((n, u, v))
    if len(found) >= 2:
        (n1, u1, v1), (n2, u2, v2) = found[-2], found[-1]
        s = np.linspace(0, 1, 1001)
        print(f"n={n1} vs n={n2} on the centrelines: max |Δu| {np.abs(u1(s) - u2(s)).max():.2e}, "
              f"max |Δv| {np.abs(v1(s) - v2(s)).max():.2e}")
    if checkpoints:
        compare_runs(checkpoints, found, ghia_u, ghia_v)


if __name__ == "__main__":
    main()
