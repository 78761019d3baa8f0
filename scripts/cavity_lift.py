#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes configs/lid_driven_cavity.yaml: the lid-driven cavity with Taylor's corner flows as a lift.

    scripts/cavity_lift.py            # rewrites configs/lid_driven_cavity.yaml
    scripts/cavity_lift.py --check    # checks the lift's closed forms and that the config is this script's

At each top corner the lid's u = 1 meets a wall's u = 0: the velocity jumps, its gradient grows
like 1/r and the pressure like 1/r. No smooth network holds that, and residual points that land
near a corner dominate the loss (the first form of the config, a harmonic lift of u alone, left
a divergence of order 1/r there, and its error at Ghia's points changed from seed to seed by 4x).

The lift here is the exact Stokes flow in a corner with one sliding wall (G. I. Taylor's
scraper, 1960). In a corner's own coordinates, s along the lid away from the corner and
q = 1 - y into the cavity, r^2 = s^2 + q^2, theta = atan2(q, s), the stream function is
phi = r f(theta), f = A sin(theta) + C theta sin(theta) + D theta cos(theta), with
D = 4/(4 - pi^2), C = D pi/2, A = -D pi^2/4 (u = 1 on the lid, no slip on the wall). In closed form

    u = A + C theta + (C s q + D s^2)/r^2,    v = D theta - (C q^2 + D s q)/r^2,
    u_x = -2K s q/r^4,  u_y = -2K s^2/r^4,  v_x = 2K q^2/r^4,  v_y = 2K s q/r^4,  K = C s - D q,
    psi = -(A q + C theta q + D theta s),  omega = v_x - u_y = 2K/r^2,  p = 2 nu (C q + D s)/r^2,

and grad p = nu lap(u, v) exactly. The right corner is the left one mirrored (x -> 1 - x, which
keeps u and psi and flips v and p). The two are blended through the stream function,
Psi = chi psi_L + (1 - chi) psi_R with chi = (1 + cos(pi x))/2 (chi' = 0 at both walls), so the
lift (U, V) = (Psi_y, -Psi_x) is divergence-free, U = 1 and V = 0 on the lid, U = V = 0 on the
side walls; P = chi p_L + (1 - chi) p_R. Near each corner chi - 1 = O(x^2), so the lift is
Taylor's flow up to terms whose second derivatives are bounded, and the Stokes remainder
S = grad P - nu lap(U, V) (written out below with chi's derivatives) is bounded everywhere.

The network's outputs are w, s, p with u = w + U, v = s + V, pressure P + p: its boundary data are
continuous (zero on the lid and the side walls, -U and -V on the bottom) and its residuals
are smooth up to the inertial term (U.grad U ~ 1/r, which a smooth correction cannot cancel;
the next term of the corner's expansion).
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
CONFIG = ROOT / "configs" / "lid_driven_cavity.yaml"


def corner(s, q):
    """Taylor's corner flow in the corner's coordinates s, q (expression texts)."""
    r2 = f"(({s})^2 + ({q})^2)"
    th = f"atan2({q}, {s})"
    k = f"(C*({s}) - D*({q}))"
    return dict(
        u=f"(A + C*{th} + (C*({s})*({q}) + D*({s})^2)/{r2})",
        v=f"(D*{th} - (C*({q})^2 + D*({s})*({q}))/{r2})",
        ux=f"(-2*{k}*({s})*({q})/{r2}^2)",
        uy=f"(-2*{k}*({s})^2/{r2}^2)",
        vx=f"(2*{k}*({q})^2/{r2}^2)",
        vy=f"(2*{k}*({s})*({q})/{r2}^2)",
        psi=f"(-(A*({q}) + C*{th}*({q}) + D*{th}*({s})))",
        om=f"(2*{k}/{r2})",
        p=f"(2*nu*(C*({q}) + D*({s}))/{r2})",
    )


def lift():
    """The blended lift's texts: U, V, their first derivatives and the Stokes remainder Sx, Sy."""
    left = corner("x", "1 - y")
    m = corner("1 - x", "1 - y")  # the left corner's fields at the mirrored point
    right = dict(u=m["u"], v=f"(-{m['v']})", ux=f"(-{m['ux']})", uy=m["uy"], vx=m["vx"], vy=f"(-{m['vy']})",
                 psi=m["psi"], om=m["om"], p=f"(-{m['p']})")
    chi, c1, c2, c3 = ("((1 + cos(pi*x))/2)", "(-(pi/2)*sin(pi*x))", "(-(pi^2/2)*cos(pi*x))",
                       "((pi^3/2)*sin(pi*x))")
    blend = lambda k: f"({chi}*{left[k]} + (1 - {chi})*{right[k]})"
    jump = lambda k: f"({left[k]} - {right[k]})"
    return dict(
        U=blend("u"),
        V=f"({blend('v')} - {c1}*{jump('psi')})",
        Ux=f"({c1}*{jump('u')} + {blend('ux')})",
        Uy=blend("uy"),
        Vx=f"(2*{c1}*{jump('v')} + {blend('vx')} - {c2}*{jump('psi')})",
        Vy=f"({blend('vy')} - {c1}*{jump('u')})",
        Sx=f"({c1}*{jump('p')} - nu*(2*{c1}*{jump('ux')} + {c2}*{jump('u')}))",
        Sy=f"(-nu*(2*{c1}*{jump('vx')} + 3*{c2}*{jump('v')} - {c3}*{jump('psi')} + {c1}*{jump('om')}))",
    )


HEADER = """\
# SPDX-License-Identifier: MIT
# Lid-driven cavity at Re = 100: steady incompressible Navier–Stokes on the unit square,
#   u u_x + v u_y + p_x − ν Δu = 0,  u v_x + v v_y + p_y − ν Δv = 0,  u_x + v_y = 0,  ν = 1/100,
# u = 1, v = 0 on the lid y = 1; u = v = 0 on the other walls (the standard problem: the lid's
# u = 1 right up to the corners, where u jumps to 0).
#
# Written by scripts/cavity_lift.py (edit it, not this file; its docstring derives the lift).
# The corners are not the network's to represent: u = w + U, v = s + V, pressure p + P, where
# (U, V, P) is G. I. Taylor's exact Stokes flow in a corner with a sliding wall, one at each top
# corner, blended through the stream function by χ = (1 + cos πx)/2. The lift is
# divergence-free, U = 1 and V = 0 on the lid, U = V = 0 on the side walls; its velocity jump,
# 1/r gradient and 1/r pressure at the corners cancel in the Stokes part of its residual, so
# the residuals below read the lift's U, V, first derivatives and bounded Stokes remainder
# S = ∇P − νΔ(U, V) in closed form (A, C, D: the corner flow's coefficients), and the network's
# w, s, p have continuous boundary data (0 on the lid and side walls; −U, −V on the bottom).
# `derived` gives u and v, which Ghia's tables are compared with. A SIREN, Adam on 2,000 new
# points a step, then Levenberg–Marquardt in double on two sets of 2,000 points (about 6,400
# residual rows against 1,347 parameters).
#
# Reference: Ghia, Ghia & Shin (1982), Tables I and II (data/ghia_re100_*_centreline.csv):
# u along x = 0.5 and v along y = 0.5; target max deviation 1e-2 of the lid speed on both.
# Ghia's own v lies 9.2e-3 from the converged solution near its minimum (second-order finite
# differences on 128² and 256², extrapolated: scripts/cavity_reference.py), which leaves a
# solver 8e-4 of error in Ghia's direction.
# Figures per seed, against Ghia and a converged solution: docs/guide.md ("Your own equation")
# and docs/experiments.md (2026-11-27).
# Run: nfield run configs/lid_driven_cavity.yaml
"""


def config_text():
    t = lift()
    return HEADER + f"""problem: pde
domain:
  lower: [0, 0]
  upper: [1, 1]
outputs: [w, s, p]
constants:
  nu: "1/100"
  D: "4/(4 - pi^2)"
  C: "2*pi/(4 - pi^2)"
  A: "-pi^2/(4 - pi^2)"
derived:
  u: "w + {t['U']}"
  v: "s + {t['V']}"
equation:
  residuals:
    - name: momentum_x
      expr: "(w + {t['U']})*(w_x + {t['Ux']}) + (s + {t['V']})*(w_y + {t['Uy']}) + {t['Sx']} + p_x - nu*lap(w)"
    - name: momentum_y
      expr: "(w + {t['U']})*(s_x + {t['Vx']}) + (s + {t['V']})*(s_y + {t['Vy']}) + {t['Sy']} + p_y - nu*lap(s)"
    - {{name: continuity, expr: "w_x + s_y"}}
    - {{name: walls_w, expr: "w", on: [y_max, x_min, x_max], batch: walls, weight: 10}}
    - {{name: walls_s, expr: "s", on: [y_max, x_min, x_max], batch: walls, weight: 10}}
    - {{name: bottom_w, expr: "w + {t['U']}", on: [y_min], batch: bottom, weight: 10}}
    - {{name: bottom_s, expr: "s + {t['V']}", on: [y_min], batch: bottom, weight: 10}}
reference:
  file:
    - {{file: ../data/ghia_re100_u_centreline.csv, outputs: [u]}}
    - {{file: ../data/ghia_re100_v_centreline.csv, outputs: [v]}}
field:
  type: siren
  hidden: [30, 30, 30]
  first_omega: 3
  hidden_omega: 1
training:
  seed: 0
  precision: double
  batch: {{interior: 2000, walls: 150, bottom: 50}}
  stages:
    - {{optimizer: adam, steps: 2000, lr: 5.0e-3, schedule: cosine, lr_final: 1.0e-4}}
    - {{optimizer: lm, steps: 200, resample_every: 100}}
output:
  dir: out/lid_driven_cavity
  grid: [101, 101]
"""


def check():
    """The closed forms against central differences, the boundary values, the bounded remainder."""
    import numpy as np
    d = 4 / (4 - math.pi ** 2)
    env = dict(A=-d * math.pi ** 2 / 4, C=d * math.pi / 2, D=d, nu=0.01, pi=math.pi, sin=np.sin, cos=np.cos,
               atan2=np.arctan2)
    value = lambda text, x, y: eval(text.replace("^", "**"), dict(env, x=x, y=y))
    one = corner("x", "1 - y")
    t = lift()
    psi = lambda x, y: value(f"((1 + cos(pi*x))/2)*{one['psi']} + (1 - (1 + cos(pi*x))/2)*"
                             + corner('1 - x', '1 - y')["psi"], x, y)
    pressure = lambda x, y: value(f"((1 + cos(pi*x))/2)*{one['p']} - (1 - (1 + cos(pi*x))/2)*"
                                  + corner('1 - x', '1 - y')["p"], x, y)
    rng = np.random.default_rng(0)
    x, y = rng.uniform(0.05, 0.95, 200), rng.uniform(0.05, 0.95, 200)
    h = 1e-4
    dx = lambda f, x, y: (f(x + h, y) - f(x - h, y)) / (2 * h)
    dy = lambda f, x, y: (f(x, y + h) - f(x, y - h)) / (2 * h)
    lap = lambda f, x, y: (f(x + h, y) + f(x - h, y) + f(x, y + h) + f(x, y - h) - 4 * f(x, y)) / h ** 2
    U = lambda x, y: dy(psi, x, y)
    V = lambda x, y: -dx(psi, x, y)
    fd = dict(U=U(x, y), V=V(x, y), Ux=dx(U, x, y), Uy=dy(U, x, y), Vx=dx(V, x, y), Vy=dy(V, x, y))
    worst = {}
    for key, approx in fd.items():
        worst[key] = np.max(np.abs(value(t[key], x, y) - approx)) / max(1, np.max(np.abs(approx)))
    h = 1e-3  # second differences of first differences: a larger step
    Sx = dx(pressure, x, y) - 0.01 * lap(lambda a, b: value(t["U"], a, b), x, y)
    Sy = dy(pressure, x, y) - 0.01 * lap(lambda a, b: value(t["V"], a, b), x, y)
    worst["Sx"] = np.max(np.abs(value(t["Sx"], x, y) - Sx))
    worst["Sy"] = np.max(np.abs(value(t["Sy"], x, y) - Sy))
    # The remainder is a second difference of a first one at h = 1e-3: O(h^2) of third derivatives.
    ok = all(v < (1e-3 if k.startswith("S") else 1e-5) for k, v in worst.items())
    print("closed forms against central differences (largest error):",
          ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
    a = np.linspace(0.01, 0.99, 99)
    walls = dict(lid_U=np.max(np.abs(value(t["U"], a, 1.0) - 1)), lid_V=np.max(np.abs(value(t["V"], a, 1.0))),
                 left=np.max(np.abs([value(t[k], 0.0, a) for k in "UV"])),
                 right=np.max(np.abs([value(t[k], 1.0, a) for k in "UV"])),
                 divergence=np.max(np.abs(value(t["Ux"], x, y) + value(t["Vy"], x, y))))
    print("boundary values and divergence (largest error):", ", ".join(f"{k} {v:.1e}" for k, v in walls.items()))
    ok &= all(v < 1e-12 for v in walls.values())
    r = 10.0 ** -np.arange(1, 7)
    near = max(np.max(np.abs(value(t[k], r * np.cos(0.7), 1 - r * np.sin(0.7)))) +
               np.max(np.abs(value(t[k], 1 - r * np.cos(0.7), 1 - r * np.sin(0.7)))) for k in ("Sx", "Sy"))
    print(f"Stokes remainder within r = 1e-6 of the corners: at most {near:.3f}")
    ok &= near < 1
    text_ok = CONFIG.read_text(encoding="utf-8") == config_text()
    if not text_ok:
        print(f"{CONFIG} is not what scripts/cavity_lift.py writes: run it")
    return ok and text_ok


if __name__ == "__main__":
    if sys.argv[1:] == ["--check"]:
        sys.exit(0 if check() else 1)
    if sys.argv[1:]:
        sys.exit(__doc__)
    CONFIG.write_text(config_text(), encoding="utf-8")
    print(f"wrote {CONFIG}")
