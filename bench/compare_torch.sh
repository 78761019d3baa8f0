#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
#
# Compare one PINN training step of `nfield bench` with the PyTorch peer
# (bench/torch_step.py: SIREN 256x4, autograd double backward, Adam), for
#   laplacian (d=2), wave (d=3), biharmonic (d=2)  x  batch 1024 4096 16384.
#
# Usage:
#   bench/compare_torch.sh BUILD_DIR [--out FILE] [--steps S] [--steps-large S]
#                                    [--threads T] [--mem-cap-gb G]
#                                    [--ops "laplacian wave biharmonic"]
#                                    [--batches "1024 4096 16384"]
#
#   BUILD_DIR       CMake build folder; the C++ side is BUILD_DIR/bin/nfield
#                   (skipped with a message when it does not exist).
#   --out FILE      JSON lines of both implementations (default
#                   BUILD_DIR/bench_torch_compare.jsonl; truncated first).
#   --steps S       timed steps per configuration for torch (default 20)
#   --steps-large S timed steps for batches >= 16384 (default 10)
#   --threads T     threads for both sides (default 2)
#   --mem-cap-gb G  address-space cap per torch process (default 20); a
#                   configuration that does not fit is reported as
#                   {"error": "out of memory"} instead of exhausting the machine.
#
# The C++ benchmark contract: `nfield bench --op OP --batch N --json` prints
# JSON lines with keys impl="nfield", op, dims, batch, median_step_ms, gflops,
# gemm_gflops, peak_rss_mb.
#
# PyTorch in Debian links libblas.so.3 (resolved through the alternatives
# system).  We put the OpenMP build of OpenBLAS first on LD_LIBRARY_PATH so
# torch uses it whatever the alternatives say, and check which library torch's
# sgemm_ actually resolves to before running anything.
set -euo pipefail

PY=/usr/bin/python3                 # Debian interpreter, the one with torch
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
TORCH_STEP="$HERE/torch_step.py"

usage() { sed -n '2,30p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit "${1:-2}"; }

[[ $# -ge 1 ]] || usage
case "$1" in -h|--help) usage 0 ;; esac
BUILD_DIR="$1"; shift
OUT=""
STEPS=20
STEPS_LARGE=10
THREADS=2
MEM_CAP_GB=20
OPS="laplacian wave biharmonic"
BATCHES="1024 4096 16384"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --steps) STEPS="$2"; shift 2 ;;
    --steps-large) STEPS_LARGE="$2"; shift 2 ;;
    --threads) THREADS="$2"; shift 2 ;;
    --mem-cap-gb) MEM_CAP_GB="$2"; shift 2 ;;
    --ops) OPS="$2"; shift 2 ;;
    --batches) BATCHES="$2"; shift 2 ;;
    -h|--help) usage 0 ;;
    *) echo "unknown option: $1" >&2; usage ;;
  esac
done
[[ -d "$BUILD_DIR" ]] || { echo "error: build dir '$BUILD_DIR' does not exist" >&2; exit 2; }
OUT="${OUT:-$BUILD_DIR/bench_torch_compare.jsonl}"
NFIELD="$BUILD_DIR/bin/nfield"

declare -A DIMS=([laplacian]=2 [wave]=3 [biharmonic]=2)

# ---------------------------------------------------------------- BLAS setup
# Directory where libopenblas0-openmp puts its libblas.so.3.
BLAS_DIR=""
if command -v dpkg >/dev/null 2>&1; then
  BLAS_LIB="$(dpkg -L libopenblas0-openmp 2>/dev/null | grep '/libblas\.so\.3$' | head -n1 || true)"
  [[ -n "$BLAS_LIB" ]] && BLAS_DIR="$(dirname "$BLAS_LIB")"
fi
BLAS_DIR="${BLAS_DIR:-/usr/lib/x86_64-linux-gnu/openblas-openmp}"
if [[ ! -e "$BLAS_DIR/libblas.so.3" ]]; then
  echo "warning: $BLAS_DIR/libblas.so.3 not found; torch uses whatever libblas.so.3 resolves to" >&2
fi
export LD_LIBRARY_PATH="$BLAS_DIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export OMP_NUM_THREADS="$THREADS"

# Which BLAS does a torch process really load, and where does sgemm_ come from?
echo "== BLAS check (LD_LIBRARY_PATH=$LD_LIBRARY_PATH, OMP_NUM_THREADS=$OMP_NUM_THREADS)"
BLAS_SEEN="$("$PY" - <<'EOF'
import os, torch
torch.ones(64, 64) @ torch.ones(64, 64)        # make sure BLAS has been used
libs = []
with open("/proc/self/maps") as fh:              # libraries mapped in this process
    for line in fh:
        p = line.split()
        if len(p) >= 6 and ("blas" in p[5] or "lapack" in p[5]) and p[5] not in libs:
            libs.append(p[5])
for l in libs:
    print(f"mapped: {l} -> {os.path.realpath(l)}")
import re
m = re.search(r"BLAS_INFO=(\w+)", torch.__config__.show())
print("torch.__config__: BLAS_INFO=" + (m.group(1) if m else "not reported")
      + " (build-time; 'generic' = the libblas.so.3 found at run time)")
EOF
)"
echo "$BLAS_SEEN"
# torch_step.py reports the library sgemm_ resolves to (via dladdr) in its
# "blas" field; take it from a tiny run so the check uses the same code path.
SGEMM_FROM="$("$PY" "$TORCH_STEP" --op laplacian --batch 16 --steps 1 --warmup 0 \
              --threads "$THREADS" 2>/dev/null | "$PY" -c 'import json,sys; print(json.loads(sys.stdin.readlines()[-1])["blas"])')"
echo "sgemm_ resolves to: $SGEMM_FROM"
if [[ "$SGEMM_FROM" != *openblas* && "$SGEMM_FROM" != *OpenBLAS* ]]; then
  echo "warning: torch is NOT using OpenBLAS; timings are not the intended peer" >&2
fi

# ---------------------------------------------------------------- runs
# Timings are only meaningful on an otherwise idle machine.
"$PY" - <<'EOF'
import os, sys
load, cpus = os.getloadavg()[0], os.cpu_count()
if load > 0.5:
    print(f"warning: 1-minute load average is {load:.2f} on {cpus} CPUs; other work "
          "will distort the step times (each torch record carries loadavg_1m_before)",
          file=sys.stderr)
EOF
: > "$OUT"
have_nfield=1
nfield_ok=0      # set once `nfield bench` has printed JSON
if [[ ! -x "$NFIELD" ]]; then
  have_nfield=0
  echo "note: $NFIELD not found; skipping the nfield side (torch only)" >&2
fi

# Append the last JSON line of $2 to $OUT, or a synthesized error record.
# $1 = fallback JSON (a record carrying the error) used when no line parses.
append_json() {
  local fallback="$1" text="$2"
  "$PY" - "$fallback" "$text" >> "$OUT" <<'EOF'
import json, sys
fallback, text = sys.argv[1], sys.argv[2]
rec = None
for line in text.splitlines():
    line = line.strip()
    if line.startswith("{"):
        try:
            rec = json.loads(line)
        except ValueError:
            pass
print(json.dumps(rec if rec is not None else json.loads(fallback)))
EOF
}

# Outer guard: the torch script caps its own address space; prlimit adds a
# slightly higher hard cap in case anything escapes that (e.g. a crash
# before the cap is set).
PRLIMIT=()
if command -v prlimit >/dev/null 2>&1; then
  PRLIMIT=(prlimit --as=$(( (MEM_CAP_GB + 1) * 1024 * 1024 * 1024 )) --)
fi

for op in $OPS; do
  d="${DIMS[$op]:?unknown op $op}"
  for n in $BATCHES; do
    steps="$STEPS"; (( n >= 16384 )) && steps="$STEPS_LARGE"

    if (( have_nfield )); then
      echo "== nfield $op d=$d batch=$n" >&2
      set +e
      txt="$("$NFIELD" bench --op "$op" --batch "$n" --json)"; rc=$?
      set -e
      if (( ! nfield_ok )) && ! grep -q '^[[:space:]]*{' <<< "$txt"; then
        # First run and no JSON at all: the binary has no working `bench`
        # subcommand yet.  Skip the C++ side instead of recording errors.
        echo "note: '$NFIELD bench' printed no JSON (rc=$rc, output: $(head -n1 <<< "$txt")); skipping the nfield side" >&2
        have_nfield=0
      else
        nfield_ok=1
        append_json "{\"impl\":\"nfield\",\"op\":\"$op\",\"dims\":$d,\"batch\":$n,\"error\":\"exit code $rc, no JSON\"}" "$txt"
      fi
    fi

    echo "== torch  $op d=$d batch=$n steps=$steps" >&2
    set +e
    txt="$("${PRLIMIT[@]}" "$PY" "$TORCH_STEP" --op "$op" --batch "$n" --steps "$steps" \
            --threads "$THREADS" --mem-cap-gb "$MEM_CAP_GB")"; rc=$?
    set -e
    # Exit code 3 is torch_step's own "out of memory" record; anything else
    # without a JSON line (killed, crashed) becomes an error record here.
    err="exit code $rc, no JSON"
    (( rc == 137 || rc == 139 || rc == 134 )) && err="out of memory"
    append_json "{\"impl\":\"torch\",\"op\":\"$op\",\"dims\":$d,\"batch\":$n,\"error\":\"$err\"}" "$txt"
  done
done

# ---------------------------------------------------------------- table
echo
echo "results: $OUT"
"$PY" - "$OUT" <<'EOF'
import json, sys
recs = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
by = {}
order = []
for r in recs:
    key = (r.get("op"), r.get("batch"))
    if key not in by:
        order.append(key)
    by.setdefault(key, {})[r.get("impl")] = r

def num(r, k):
    v = r.get(k) if r else None
    return v if isinstance(v, (int, float)) else None

def cell(v, fmt):
    return format(v, fmt) if v is not None else "-"

def ms(r):
    if r is None:
        return "skipped"
    if "error" in r:
        return "OOM" if r["error"] == "out of memory" else "error"
    return cell(num(r, "median_step_ms"), ".1f")

hdr = ["op", "batch", "nfield ms", "torch ms", "speed-up", "nfield MB", "torch MB", "torch +MB", "mem ratio"]
rows = []
for op, n in order:
    a, b = by[(op, n)].get("nfield"), by[(op, n)].get("torch")
    ta, tb = num(a, "median_step_ms"), num(b, "median_step_ms")
    # torch's increase over its idle process (interpreter, libtorch, model): its whole
    # ru_maxrss would count a baseline that nfield's peak after a reset does not hold.
    ma, mb, ib = num(a, "peak_rss_mb"), num(b, "peak_rss_mb"), num(b, "step_rss_increase_mb")
    ok_a = a is not None and "error" not in a
    ok_b = b is not None and "error" not in b
    rows.append([op, str(n), ms(a), ms(b),
                 cell(tb / ta, ".2f") + "x" if ok_a and ok_b and ta else "-",
                 cell(ma, ".0f") if ok_a else "-",
                 cell(mb, ".0f") if b is not None else "-",   # peak RSS up to the OOM too
                 cell(ib, ".0f") if b is not None else "-",
                 cell(ib / ma, ".2f") + "x" if ok_a and ok_b and ma and ib is not None else "-"])
w = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(hdr)]
print("  ".join(h.rjust(w[i]) for i, h in enumerate(hdr)))
for r in rows:
    print("  ".join(c.rjust(w[i]) for i, c in enumerate(r)))
print("speed-up = torch ms / nfield ms; torch MB = its process's peak RSS, torch +MB = that peak "
      "less the RSS of its idle process (imports, model, optimizer, batches; before the first "
      "step); mem ratio = torch +MB / nfield MB (nfield's peak RSS after a reset, its own "
      "process baseline included).")
EOF
