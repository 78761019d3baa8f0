#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes configs/navier_stokes_cylinder.yaml: steady flow past a cylinder (Schäfer & Turek 2D-1).

    scripts/cylinder_flow.py            # rewrites configs/navier_stokes_cylinder.yaml
    scripts/cylinder_flow.py --check    # checks the ansatz's derivatives and that the config is this script's

The benchmark (Schäfer & Turek 1996, case 2D-1): the channel [0, 2.2] x [0, H], H = 0.41, minus
the disk of radius 0.05 at (0.2, 0.2); nu = 1e-3, rho = 1; inflow u = U(y) = 4 Um y (H - y)/H^2,
Um = 0.3, v = 0; no slip on the walls and the cylinder; do-nothing outflow nu du/dn - p n = 0
at x = 2.2. Re = Ubar D/nu = 20 with Ubar = 2 Um/3 = 0.2, D = 0.1.

Mass and the walls are exact by construction. The velocity is that of a stream function,
u = psi_y, v = -psi_x (divergence-free for any network: a soft continuity residual let a first
network lose a third of the flux by x = 2.2), and

    psi = Psi(y) + S G(x) K(y) n(x, y),   Psi' = U,
    G = (1 - exp(-x/a))^2,   K = (4 y (H - y)/H^2)^2,

with n the network's first output. G and K vanish to second order at the inlet and on the
walls, so there psi = Psi and grad psi = grad Psi for every n: u = U, v = 0 at x = 0 and
u = v = 0 on y = 0, H. S = 0.1 keeps n of order one (psi - Psi is at most a few hundredths);
a = 0.2 lets the correction grow over a fifth of the channel's length ahead of the cylinder
(a = 0.05 asked n for a steep layer at the inlet, where the residual then stayed large). The
cylinder's no-slip and the outflow stay soft residuals, and so does momentum:

    psi_y psi_xy - psi_x psi_yy + p_x - nu (psi_xxy + psi_yyy) = 0,
    psi_x psi_xy - psi_y psi_xx + p_y + nu (psi_xxx + psi_xyy) = 0,

where each derivative of psi is written out by Leibniz' rule over the product (G K depends on
x and y separately, so its derivatives are products of G's and K's). The network's derivative
symbols go up to third order (Taylor streams, solvers/problems/pde_streams.h).

Figures: the force on the cylinder F = int_S (p n - nu (grad u + grad u^T) n) dS with n the
domain's normal (into the cylinder), C_D = 2 F_x/(Ubar^2 D) = 500 F_x, C_L = 500 F_y, and
Delta p = p(0.15, 0.2) - p(0.25, 0.2); the `functionals` section computes them, against the
reference values of John & Matthies / Nabh (C_D 5.57953523384, C_L 0.010618948146,
Delta p 0.11752016697).
"""
import argparse
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
CONFIG = ROOT / "configs" / "navier_stokes_cylinder.yaml"

# The config's constants (the check evaluates the expressions with the same values).
CONSTANTS = dict(nu=1e-3, H=0.41, Um=0.3, a=0.2, S=0.1)

E = "exp(-x/a)"
G = [f"(1 - {E})^2", f"(2*(1 - {E})*{E}/a)", f"(2*({E}^2 - (1 - {E})*{E})/a^2)",
     f"(2*((1 - {E})*{E} - 3*{E}^2)/a^3)"]
HY = "(4*y*(H - y)/H^2)"
H1 = "(4*(H - 2*y)/H^2)"
K = [f"{HY}^2", f"(2*{HY}*{H1})", f"(2*({H1}^2 - 8*{HY}/H^2))", f"(-48*{H1}/H^2)"]
PSI = ["(4*Um*(H*y^2/2 - y^3/3)/H^2)", "(4*Um*y*(H - y)/H^2)", "(4*Um*(H - 2*y)/H^2)", "(-8*Um/H^2)"]


def network_symbol(i, j):
    return "n" if i == j == 0 else "n_" + "x" * i + "y" * j


def psi(i, j):
    """The text of d^i/dx^i d^j/dy^j psi."""
    terms = []
    if i == 0:
        terms.append(PSI[j])
    for a in range(i + 1):
        for b in range(j + 1):
            c = math.comb(i, a) * math.comb(j, b)
            factor = (f"{c}*" if c > 1 else "") + f"S*{G[a]}*{K[b]}*{network_symbol(i - a, j - b)}"
            terms.append(factor)
    return "(" + " + ".join(terms) + ")"


def residuals():
    d = {(i, j): psi(i, j) for i in range(4) for j in range(4) if i + j <= 3}
    u, v = d[0, 1], f"(-{d[1, 0]})"
    ux, uy, vx, vy = d[1, 1], d[0, 2], f"(-{d[2, 0]})", f"(-{d[1, 1]})"
    mx = f"{d[0, 1]}*{d[1, 1]} - {d[1, 0]}*{d[0, 2]} + p_x - nu*({d[2, 1]} + {d[0, 3]})"
    my = f"{d[1, 0]}*{d[1, 1]} - {d[0, 1]}*{d[2, 0]} + p_y + nu*({d[3, 0]} + {d[1, 2]})"
    drag = f"500*(p*nx - nu*(2*{ux}*nx + ({uy} + {vx})*ny))"
    lift = f"500*(p*ny - nu*(({uy} + {vx})*nx + 2*{vy}*ny))"
    return dict(u=u, v=v, ux=ux, vx=vx, mx=mx, my=my, drag=drag, lift=lift, psi=d)


HEADER = """\
# SPDX-License-Identifier: MIT
# Steady flow past a cylinder at Re = 20: the Schäfer–Turek benchmark 2D-1 (Schäfer & Turek
# 1996), with `problem: pde`. Channel [0, 2.2] x [0, 0.41] minus the disk r = 0.05 at
# (0.2, 0.2); nu = 1e-3; parabolic inflow (Um = 0.3), no slip on the walls and the cylinder,
# do-nothing outflow. Targets: drag coefficient within 2 % of 5.5795, lift within 10 % of
# 0.0106, pressure difference p(0.15, 0.2) - p(0.25, 0.2) within 2 % of 0.1175.
#
# Written by scripts/cylinder_flow.py (edit it, not this file; its docstring derives the
# ansatz). The velocity is (psi_y, -psi_x) with psi = Psi(y) + S G(x) K(y) n: divergence-free,
# and the inflow and the walls hold for any network n; the cylinder and the outflow are soft
# residuals. The channel is three boxes intersected so that its inlet, outlet and walls are
# parts of their own. `functionals` integrates the force on the cylinder (drag, lift) and
# takes the pressure difference; their figures go to the progress line and metrics.json.
# Figures: docs/guide.md ("Your own equation") and docs/experiments.md.
# Run: nfield run configs/navier_stokes_cylinder.yaml
"""


def config_text():
    r = residuals()
    near = '"(x - 0.2)^2 + (y - 0.2)^2 < 0.015"'
    lines = [
        "problem: pde",
        "domain:",
        "  geometry:",
        "    shape: difference",
        "    shapes:",
        "      - shape: intersection",
        "        shapes:",
        "          - {shape: box, name: inlet, lower: [0, -1], upper: [5, 1.41]}",
        "          - {shape: box, name: outlet, lower: [-1, -1], upper: [2.2, 1.41]}",
        "          - {shape: box, name: walls, lower: [-1, 0], upper: [3.2, 0.41]}",
        "      - {shape: disk, name: cylinder, center: [0.2, 0.2], radius: 0.05}",
        "outputs: [n, p]",
        "constants:",
        *[f'  {k}: "{v:g}"' for k, v in CONSTANTS.items()],
        "equation:",
        "  residuals:",
        f'    - {{name: momentum_x, expr: "{r["mx"]}"}}',
        f'    - {{name: momentum_y, expr: "{r["my"]}"}}',
        f'    - {{name: near_x, expr: "{r["mx"]}", where: {near}, batch: near}}',
        f'    - {{name: near_y, expr: "{r["my"]}", where: {near}, batch: near}}',
        f'    - {{name: cylinder_u, expr: "{r["u"]}", on: cylinder, batch: cylinder, weight: 10}}',
        f'    - {{name: cylinder_v, expr: "{r["v"]}", on: cylinder, batch: cylinder, weight: 10}}',
        f'    - {{name: outflow_x, expr: "nu*{r["ux"]} - p", on: outlet, batch: outlet}}',
        f'    - {{name: outflow_y, expr: "nu*{r["vx"]}", on: outlet, batch: outlet}}',
        "functionals:",
        f'  drag: {{integral: "{r["drag"]}", on: cylinder, reference: 5.57953523384}}',
        f'  lift: {{integral: "{r["lift"]}", on: cylinder, reference: 0.010618948146}}',
        "  delta_p: {value: p, at: [[0.15, 0.2], [0.25, 0.2]], coefficients: [1, -1], reference: 0.11752016697}",
        "field:",
        "  type: siren",
        "  hidden: [32, 32, 32]",
        "  first_omega: 30",
        "  hidden_omega: 1",
        "training:",
        "  seed: 0",
        "  precision: double",
        "  sampler: sobol",
        "  batch: {interior: 3000, near: 1500, cylinder: 300, outlet: 100}",
        "  stages:",
        "    - {optimizer: adam, steps: 500, lr: 3.0e-3, schedule: cosine, lr_final: 1.0e-4}",
        "    - {optimizer: lm, steps: 300, resample_every: 50}",
        "    - {optimizer: lm, steps: 40, batch_scale: 3}",
        "output:",
        "  dir: out/navier_stokes_cylinder",
        "  grid: [441, 83]",
    ]
    return HEADER + "\n".join(lines) + "\n"


def evaluate(text, x, y, n):
    """Evaluates an expression text at (x, y) with the network symbols from n(i, j)."""
    names = dict(exp=math.exp, x=x, y=y, **CONSTANTS)
    for i in range(4):
        for j in range(4 - i):
            names[network_symbol(i, j)] = n(i, j, x, y)
    return eval(text.replace("^", "**"), {"__builtins__": {}}, names)


def check():
    # A smooth test network: n = sin(2x + 1) cos(3y) + x y^2, derivatives in closed form.
    def n(i, j, x, y):
        sx = [math.sin(2 * x + 1), 2 * math.cos(2 * x + 1), -4 * math.sin(2 * x + 1), -8 * math.cos(2 * x + 1)][i]
        cy = [math.cos(3 * y), -3 * math.sin(3 * y), -9 * math.cos(3 * y), 27 * math.sin(3 * y)][j]
        poly = {(0, 0): x * y * y, (1, 0): y * y, (0, 1): 2 * x * y, (1, 1): 2 * y, (0, 2): 2 * x, (1, 2): 2}.get((i, j), 0)
        return sx * cy + poly

    r = residuals()
    d = r["psi"]
    failures = []
    h = 2.5e-4
    for (x, y) in [(0.3, 0.1), (1.1, 0.33), (0.07, 0.2), (2.0, 0.02)]:
        for (i, j), text in d.items():
            if i + j == 0:
                continue
            # Central differences of the next lower derivative along x (or y when i = 0).
            lower, axis = ((i - 1, j), 0) if i > 0 else ((i, j - 1), 1)
            dx, dy = (h, 0) if axis == 0 else (0, h)
            f = [evaluate(d[lower], x + k * dx, y + k * dy, n) for k in (-2, -1, 1, 2)]
            fd = (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * h)  # fourth order: error ~ h^4
            exact = evaluate(text, x, y, n)
            if abs(fd - exact) > 1e-7 * max(1.0, abs(exact)):
                failures.append(f"psi_{'x' * i}{'y' * j} at ({x}, {y}): {exact:.9g} vs difference {fd:.9g}")
    # Inflow and walls hold for any n.
    for y in [0.0, 0.1, 0.3, CONSTANTS["H"]]:
        u, v = evaluate(r["u"], 0.0, y, n), evaluate(r["v"], 0.0, y, n)
        U = 4 * CONSTANTS["Um"] * y * (CONSTANTS["H"] - y) / CONSTANTS["H"] ** 2
        if abs(u - U) > 1e-12 or abs(v) > 1e-12:
            failures.append(f"inflow at y = {y}: u {u:.3g} (U {U:.3g}), v {v:.3g}")
    for x in [0.0, 0.5, 2.2]:
        for y in [0.0, CONSTANTS["H"]]:
            u, v = evaluate(r["u"], x, y, n), evaluate(r["v"], x, y, n)
            if abs(u) > 1e-12 or abs(v) > 1e-12:
                failures.append(f"wall at ({x}, {y}): u {u:.3g}, v {v:.3g}")
    if CONFIG.read_text() != config_text():
        failures.append(f"{CONFIG} is not what this script writes: run scripts/cylinder_flow.py")
    for f in failures:
        print("FAIL", f)
    print("cylinder_flow: " + ("ok" if not failures else f"{len(failures)} failures"))
    return 1 if failures else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="check the ansatz and that the config is in sync")
    args = parser.parse_args()
    if args.check:
        return check()
    CONFIG.write_text(config_text())
    print(f"wrote {CONFIG}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
