#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
#
# Data-parallel training on one machine: steps/s of the same Adam run as 1 rank × 2 threads
# and as 2 ranks × 1 thread (mpirun), and the bytes each rank sends into the step's sums.
# The run is Poisson in 2-D on a SIREN of three hidden layers of 256 (132,609 parameters),
# float, a batch of 4096 interior and 1024 boundary points, Adam.
#
# Usage: bench/mpi_scaling.sh BUILD_DIR [--steps S] [--out DIR]
#   --steps S  Adam steps per run (default 100); steps/s = 1000 / step_ms_median
#   --out DIR  scratch folder (default BUILD_DIR/bench_mpi)
# Prints one line per layout and a JSON line each; needs a build with NFIELD_MPI.
set -euo pipefail
build=${1:?usage: bench/mpi_scaling.sh BUILD_DIR [--steps S] [--out DIR]}
shift
steps=100
out=$build/bench_mpi
while [[ $# -gt 0 ]]; do
  case $1 in
    --steps) steps=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
nfield=$build/bin/nfield
mkdir -p "$out"
cat >"$out/config.yaml" <<EOF
problem: poisson
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: "-2*pi^2*sin(pi*x)*sin(pi*y)", exact: "sin(pi*x)*sin(pi*y)"}
conditions: [{on: boundary, type: dirichlet, value: "0", weight: 10}]
field: {type: siren, hidden: [256, 256, 256], first_omega: 3, hidden_omega: 1}
training:
  precision: float
  batch: {interior: 4096, boundary: 1024}
  log_every: 1000000
  stages: [{optimizer: adam, steps: $steps, lr: 1.0e-4}]
output: {dir: $out/unused, grid: [16, 16], png: false}
EOF
# OpenMPI needs these flags on a 2-core machine and as root; other MPIs take neither.
launcher=(mpirun)
if mpirun --version 2>&1 | grep -q "Open MPI"; then
  launcher+=(--oversubscribe --allow-run-as-root --bind-to none)
fi

report() {
  python3 - "$1" "$2" "$3" <<'PYEOF'
import json, sys
layout, ranks, path = sys.argv[1], int(sys.argv[2]), sys.argv[3]
m = json.load(open(path))
sps = 1000.0 / m["step_ms_median"]
per_step = m.get("mpi_bytes_per_step", 0)
print(f"{layout:<22} {sps:8.2f} steps/s  ({m['step_ms_median']:.1f} ms a step)"
      f"  {per_step:,.0f} bytes sent per rank and step  loss {m['loss']:.4e}")
print(json.dumps({"bench": "mpi_scaling", "layout": layout, "ranks": ranks,
                  "steps_per_s": sps, "step_ms_median": m["step_ms_median"],
                  "bytes_per_step_per_rank": per_step, "parameters": m["parameters"],
                  "loss": m["loss"]}))
PYEOF
}

OMP_NUM_THREADS=2 "$nfield" run "$out/config.yaml" --out "$out/r1t2" >"$out/r1t2.log"
report "1 rank x 2 threads" 1 "$out/r1t2/metrics.json"
OMP_NUM_THREADS=1 "${launcher[@]}" -np 2 "$nfield" run "$out/config.yaml" \
  --out "$out/r2t1" >"$out/r2t1.log"
report "2 ranks x 1 thread" 2 "$out/r2t1/metrics.json"
