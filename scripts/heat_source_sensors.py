#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Sensor time series of configs/heat_source.yaml: u* at 20 fixed points of [0, 1]^2, every
0.05 in t in [0, 1] (21 times, 420 rows), written to configs/data/heat_source_sensors.csv.

The manufactured solution (its derivation is in the config's header):
  u*(x, y, t) = exp(-2 pi^2 kappa t) sin(pi x) sin(pi y) + psi(x, y),
  psi = c [-(x^2 + y^2)/(4 kappa) - x^3/(6 kappa) + 0.8 sin(2 pi x) sin(pi y)/(5 pi^2 kappa)],
so that u*_t - kappa lap(u*) = s(x, y) = c (1 + x + 0.8 sin(2 pi x) sin(pi y)), kappa = 0.1,
c = 0.2 (psi then spans [-1.33, 0], the size of the transient).
The sensors are uniform in [0.05, 0.95]^2 from numpy's default_rng(26); no noise.
Run: python3 scripts/heat_source_sensors.py  (from the repository root)
"""
import numpy as np

KAPPA = 0.1
C = 0.2


def u_exact(x, y, t):
    psi = C * (-(x**2 + y**2) / (4 * KAPPA) - x**3 / (6 * KAPPA)
           + 0.8 * np.sin(2 * np.pi * x) * np.sin(np.pi * y) / (5 * np.pi**2 * KAPPA))
    return np.exp(-2 * np.pi**2 * KAPPA * t) * np.sin(np.pi * x) * np.sin(np.pi * y) + psi


def main():
    rng = np.random.default_rng(26)
    sensors = rng.uniform(0.05, 0.95, size=(20, 2))
    times = np.linspace(0.0, 1.0, 21)
    with open("configs/data/heat_source_sensors.csv", "w") as f:
        f.write("x,y,t,u\n")
        for x, y in sensors:
            for t in times:
                f.write(f"{x:.17g},{y:.17g},{t:.17g},{u_exact(x, y, t):.17g}\n")


if __name__ == "__main__":
    main()
