#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Regenerates the README's gallery (docs/images/gallery_*.png) from runs of shipped configs:
#   1. poisson_plate_with_holes.yaml  u on a plate with four holes (a shaped domain)
#   2. allen_cahn_1d.yaml       u(x, t) of the Allen–Cahn equation (x across, t upward)
#   3. sdf_bunny.yaml           the zero level set of the bunny's signed distance field
#   4. nerf_bunny_hash_grid.yaml  a held-out test view beside its ground truth
#   5. autoint_cos.yaml         an integrand and the derivative of its trained antiderivative
# Usage: scripts/make_gallery.sh [OUT]   (runs in OUT, default out/gallery; about 15 minutes
# on 2 quiet cores, most of it the 10-minute radiance field). NFIELD_ARGS adds arguments to
# every run (e.g. "--set training.threads=1"); PYTHON names a python3 with NumPy and Pillow.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/gallery}
nfield=${NFIELD:-build/bin/nfield}
mkdir -p "$out" docs/images
for config in poisson_plate_with_holes allen_cahn_1d sdf_bunny nerf_bunny_hash_grid autoint_cos; do
  extra=()
  # u(x, t) as a picture needs more frames than the config writes (one row each).
  [[ $config == allen_cahn_1d ]] && extra=(--set output.frames=192)
  # shellcheck disable=SC2086
  "$nfield" run "configs/$config.yaml" --out "$out/$config" "${extra[@]}" ${NFIELD_ARGS:-}
done
"${PYTHON:-python3}" scripts/render_mesh.py "$out/sdf_bunny/surface.ply" "$out/sdf_bunny/surface.png" --size 384
"${PYTHON:-python3}" scripts/compose_gallery.py "$out" docs/images
