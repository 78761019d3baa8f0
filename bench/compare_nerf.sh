#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
#
# Radiance-field training and rendering, nfield beside PyTorch in one run:
# `nfield bench --nerf` (configs/nerf_bunny.yaml) and bench/torch_nerf.py (the same
# network, sampling, rendering, loss and Adam), then the ratios
#   rays/s:   nfield / torch       frame ms: torch / nfield   (> 1: nfield faster)
#
# Usage:
#   bench/compare_nerf.sh BUILD_DIR [--out FILE] [--steps S] [--warmup W] [--threads T]
#                                   [--rays R] [--render-stride K] [--render-repeats N]
#
#   BUILD_DIR          CMake build folder; the C++ side is BUILD_DIR/bin/nfield
#   --out FILE         both JSON lines (default BUILD_DIR/bench_nerf_compare.jsonl)
#   --steps S          timed training steps on both sides (default 20), after
#   --warmup W         untimed ones (default 3)
#   --threads T        threads on both sides (default 2)
#   --rays R           rays per step (default 1024, as the config)
#   --render-stride K  render every k-th pixel of every k-th row of the view (default 1)
#   --render-repeats N timed renders of the view (default 3)
#
# Torch runs on Debian's python3-torch with the OpenMP build of OpenBLAS put first on
# LD_LIBRARY_PATH (as bench/compare_torch.sh does); the torch record names the BLAS
# libraries its process mapped.
set -euo pipefail

PY=/usr/bin/python3
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(dirname "$HERE")"

usage() { sed -n '2,22p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit "${1:-2}"; }

[[ $# -ge 1 ]] || usage
case "$1" in -h|--help) usage 0 ;; esac
BUILD_DIR="$1"; shift
OUT=""
STEPS=20
WARMUP=3
THREADS=2
RAYS=1024
STRIDE=1
REPEATS=3
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --steps) STEPS="$2"; shift 2 ;;
    --warmup) WARMUP="$2"; shift 2 ;;
    --threads) THREADS="$2"; shift 2 ;;
    --rays) RAYS="$2"; shift 2 ;;
    --render-stride) STRIDE="$2"; shift 2 ;;
    --render-repeats) REPEATS="$2"; shift 2 ;;
    -h|--help) usage 0 ;;
    *) echo "unknown option: $1" >&2; usage ;;
  esac
done
NFIELD="$BUILD_DIR/bin/nfield"
[[ -x "$NFIELD" ]] || { echo "error: $NFIELD not found (build it first)" >&2; exit 2; }
OUT="${OUT:-$BUILD_DIR/bench_nerf_compare.jsonl}"

BLAS_DIR=""
if command -v dpkg >/dev/null 2>&1; then
  BLAS_LIB="$(dpkg -L libopenblas0-openmp 2>/dev/null | grep '/libblas\.so\.3$' | head -n1 || true)"
  [[ -n "$BLAS_LIB" ]] && BLAS_DIR="$(dirname "$BLAS_LIB")"
fi
BLAS_DIR="${BLAS_DIR:-/usr/lib/x86_64-linux-gnu/openblas-openmp}"
[[ -e "$BLAS_DIR/libblas.so.3" ]] ||
  echo "warning: $BLAS_DIR/libblas.so.3 not found; torch uses whatever libblas.so.3 resolves to" >&2

"$PY" -c 'import os, sys
load = os.getloadavg()[0]
if load > 0.5:
    print(f"warning: 1-minute load average is {load:.2f}: other work distorts the timings", file=sys.stderr)'

COMMON=(--steps "$STEPS" --warmup "$WARMUP" --threads "$THREADS" --rays "$RAYS"
        --render-stride "$STRIDE" --render-repeats "$REPEATS")
echo "== nfield bench --nerf ${COMMON[*]}" >&2
NFIELD_JSON="$("$NFIELD" bench --nerf --json --config "$ROOT/configs/nerf_bunny.yaml" "${COMMON[@]}" | tail -n1)"
echo "== torch_nerf.py ${COMMON[*]}" >&2
TORCH_JSON="$(LD_LIBRARY_PATH="$BLAS_DIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" OMP_NUM_THREADS="$THREADS" \
              "$PY" "$HERE/torch_nerf.py" --data "$ROOT/data/multiview/bunny_blender" "${COMMON[@]}" | tail -n1)"
printf '%s\n%s\n' "$NFIELD_JSON" "$TORCH_JSON" > "$OUT"

"$PY" - "$OUT" <<'EOF'
import json, sys
a, b = (json.loads(l) for l in open(sys.argv[1]) if l.strip())
if "openblas" not in b.get("blas", "").lower():
    print(f"warning: torch did not map OpenBLAS ({b.get('blas')}); not the intended peer", file=sys.stderr)
rows = [
    ("rays/s", a["rays_per_s"], b["rays_per_s"], a["rays_per_s"] / b["rays_per_s"], "nfield / torch"),
    ("median step ms", a["median_step_ms"], b["median_step_ms"], None, ""),
    ("samples/step", a["samples_per_step"], b["samples_per_step"], None, ""),
    (f"ms/frame ({a['frame_pixels']} px)", a["frame_ms"], b["frame_ms"], b["frame_ms"] / a["frame_ms"],
     "torch / nfield"),
]
print(f"{'':24} {'nfield':>10} {'torch':>10} {'ratio':>8}")
for name, x, y, r, how in rows:
    print(f"{name:24} {x:10.1f} {y:10.1f} {(f'{r:.2f}x' if r else ''):>8}  {how}")
print(f"nfield step: network passes {100 * a['share_network']:.1f} %, rendering loss "
      f"{100 * a['share_rendering']:.1f} %, drawing rays {100 * a['share_sampling']:.1f} %, "
      f"Adam {100 * a['share_adam']:.1f} %")
print(f"nfield dense products: {a['mlp_gflops']:.1f} GFLOP/s in the network passes = "
      f"{100 * a['mlp_gemm_ratio']:.0f} % of plain Eigen products of the same shapes "
      f"({a['gemm_gflops']:.1f} GFLOP/s)")
if "fma_peak_gflops" in a:
    need = 3 * a["step_gflop"] / (b["median_step_ms"] * 1e-3)  # nfield's step in a third of torch's
    print(f"this machine's float FMA peak ({a['threads']} threads, same run): {a['fma_peak_gflops']:.1f} GFLOP/s; "
          f"nfield's network passes use {100 * a['mlp_peak_ratio']:.0f} % of it")
    print(f"3x torch's rays/s needs the step's {a['step_gflop']:.2f} GFLOP of products "
          f"at {need:.1f} GFLOP/s = {100 * need / a['fma_peak_gflops']:.0f} % of that peak")
print(f"threads {a['threads']} / {b['threads']}; torch {b['torch']}, BLAS {b['blas']}; results in {sys.argv[1]}")
EOF
