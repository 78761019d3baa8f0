#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
#
# Did a refactor change what nfield computes? Runs shipped configs for a few steps per stage
# with two nfield binaries (say, a build of main and a build of the branch) and compares
# their metrics.json exactly: the final loss and every figure except wall times and the
# version. A run repeats bit for bit for a given thread count (docs/design.md), so any
# difference, down to the last bit, is a change of behaviour.
#
# Usage: bench/compare_behaviour.sh OLD_NFIELD NEW_NFIELD [--steps N] [--lm-steps N]
#                                   [--keep DIR] [CONFIG ...]
#   --steps N     steps of every Adam and L-BFGS stage (default 20)
#   --lm-steps N  iterations of every Levenberg–Marquardt stage (default 3)
#   --keep DIR    write the runs' outputs under DIR/old and DIR/new and keep them
#   CONFIG ...    configs to run instead of the list below
# Prints one line per config and exits non-zero on any difference or failed run.
#
# The configs it runs, and what of the code each one reaches:
#   configs/poisson_2d.yaml               Laplacian residual, soft Dirichlet, Adam + L-BFGS
#   configs/poisson_2d_hash_grid.yaml     hash-grid encoding (smoothstep levels)
#   configs/helmholtz_2d.yaml             Helmholtz residual without a layer
#   configs/helmholtz_pml.yaml            PML residual (complex coefficients), LM, new points
#   configs/eikonal_constant.yaml         eikonal residual, factored
#   configs/eikonal_layered.yaml          two layers, viscosity
#   configs/wave_1d.yaml                  wave residual, soft initial conditions
#   configs/accuracy_wave_1d.yaml         hard conditions (the ansatz), LM
#   configs/autoint_cos.yaml              AutoInt in 1-D (the tangent stream)
#   configs/poisson_image.yaml            gradient supervision
#   configs/poisson_image_laplacian.yaml  energy form with a stream function, border term
#   configs/fit_image.yaml                fitting an image (linear hash grid)
#   configs/nerf_bunny.yaml               NeRF: softplus density, occupancy grid
#   configs/nerf_bunny_hash_grid.yaml     NeRF: truncated-exp density
#   configs/autoint_bunny.yaml            AutoInt along rays
set -euo pipefail

usage() { sed -n '/^# Usage:/,/^# Prints/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }

[[ $# -ge 2 ]] || usage
old_bin=$(realpath "$1") new_bin=$(realpath "$2")
shift 2
steps=20 lm_steps=3 keep="" configs=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --steps) steps=$2; shift 2 ;;
    --lm-steps) lm_steps=$2; shift 2 ;;
    --keep) keep=$2; shift 2 ;;
    -h|--help) usage ;;
    *) configs+=("$1"); shift ;;
  esac
done
[[ -x $old_bin && -x $new_bin ]] || { echo "not executable: $old_bin or $new_bin" >&2; exit 2; }

repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
if [[ ${#configs[@]} -eq 0 ]]; then
  configs=(poisson_2d poisson_2d_hash_grid helmholtz_2d helmholtz_pml eikonal_constant
           eikonal_layered wave_1d accuracy_wave_1d autoint_cos poisson_image
           poisson_image_laplacian fit_image nerf_bunny nerf_bunny_hash_grid autoint_bunny)
  configs=("${configs[@]/#/configs/}")
  configs=("${configs[@]/%/.yaml}")
fi

status=0
if [[ -n $keep ]]; then
  work=$keep
  mkdir -p "$work"
else
  work=$(mktemp -d)
  trap '[[ $status -eq 0 ]] && rm -rf "$work"' EXIT  # a failed run's log stays
fi

# --set arguments that cut every stage of CONFIG to a few steps, and drop the wall-time
# budgets: a stage with `seconds` schedules by the time spent, which no two runs share.
stage_overrides() {
  python3 - "$1" "$steps" "$lm_steps" <<'EOF'
import sys, yaml
config, steps, lm_steps = sys.argv[1], sys.argv[2], sys.argv[3]
with open(config) as f:
    stages = (yaml.safe_load(f).get("training") or {}).get("stages") or []
for i, stage in enumerate(stages):
    n = lm_steps if str(stage.get("optimizer", "")).lower() == "lm" else steps
    print(f"--set\ntraining.stages[{i}].steps={n}")
    if "seconds" in stage:
        print(f"--set\ntraining.stages[{i}].seconds=0")
EOF
}

# Prints "LOSS COUNT" if equal, else the first differences; exit status 1 on a difference.
compare_metrics() {
  python3 - "$1" "$2" <<'EOF'
import json, re, sys
# Wall times differ from run to run; what was computed does not.
untimed = re.compile(r"(^|_)(wall_s|seconds|s|ms|ms_median|step_ms_median)$|(^|_)(time|ms|us)(_|$)"
                     r"|speedup|nfield_version")
def flatten(value, key=""):
    if isinstance(value, dict):
        for k, v in value.items():
            if not untimed.search(k):
                yield from flatten(v, f"{key}.{k}" if key else k)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from flatten(v, f"{key}[{i}]")
    else:
        yield key, value
old, new = (dict(flatten(json.load(open(p)))) for p in sys.argv[1:3])
differences = [f"{k}: {old.get(k)!r} -> {new.get(k)!r}"
               for k in sorted(set(old) | set(new)) if repr(old.get(k)) != repr(new.get(k))]
if differences:
    print("; ".join(differences[:3]) + (f" (+{len(differences) - 3} more)" if len(differences) > 3 else ""))
    sys.exit(1)
print(repr(old.get("loss")), len(old))
EOF
}

printf '%-42s %-24s %-7s %s\n' config loss values result
for config in "${configs[@]}"; do
  name=$(basename "$config" .yaml)
  mapfile -t sets < <(stage_overrides "$config")
  failed=""
  for side in old new; do
    bin=$old_bin
    [[ $side == new ]] && bin=$new_bin
    out="$work/$side/$name"
    rm -rf "$out"
    if ! "$bin" run "$config" "${sets[@]}" --out "$out" --progress plain >"$work/$side-$name.log" 2>&1; then
      failed="$side run failed (log: $work/$side-$name.log)"
      break
    fi
  done
  if [[ -n $failed ]]; then
    printf '%-42s %-24s %-7s %s\n' "$config" - - "FAILED: $failed"
    status=1
    continue
  fi
  if result=$(compare_metrics "$work/old/$name/metrics.json" "$work/new/$name/metrics.json"); then
    read -r loss count <<<"$result"
    printf '%-42s %-24s %-7s %s\n' "$config" "$loss" "$count" equal
  else
    printf '%-42s %-24s %-7s %s\n' "$config" - - "DIFFERENT: $result"
    status=1
  fi
done
exit $status
