#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `make demo`: solves configs/poisson_2d.yaml and says where the outputs are.
set -euo pipefail
build=${1:-build}
"$build/bin/nfield" run configs/poisson_2d.yaml --out out/poisson_2d
echo
echo "Outputs in out/poisson_2d/:"
echo "  metrics.json   errors (rel_l2, max_abs_err), losses, step times"
echo "  solution.vti   u, grad_u, residual, exact_u, error_u  (open in ParaView)"
echo "  solution.png   preview of u"
echo "  checkpoint.h5  the trained field (h5py: f['field/layers/0/weight'])"
echo "  config.yaml    the config as resolved"
