#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""rel_l2 and max |error| per output of an `nfield run` output grid (solution.vti, or the frames
of solution.pvd), from its exact_<name> and error_<name> arrays: the per-output figures that
metrics.json sums over all outputs.

    scripts/vti_errors.py out/kovasznay/solution.vti

Reads VTK XML image data written by nfield (appended raw data, zlib blocks, UInt64 headers)
with numpy only."""
import re
import struct
import sys
import zlib
from pathlib import Path

import numpy as np


def read_arrays(path):
    data = Path(path).read_bytes()
    head, _, tail = data.partition(b'<AppendedData encoding="raw">')
    blob = tail[tail.index(b"_") + 1:]
    arrays = {}
    for m in re.finditer(rb'<DataArray type="(\w+)" Name="(\w+)"[^>]*offset="(\d+)"', head):
        kind, name, offset = m.group(1).decode(), m.group(2).decode(), int(m.group(3))
        dtype = {"Float64": "<f8", "Float32": "<f4"}.get(kind)
        if dtype is None:
            continue
        n_blocks, = struct.unpack_from("<Q", blob, offset)
        sizes = struct.unpack_from("<%dQ" % (3 + n_blocks), blob, offset)[3:]
        at = offset + 8 * (3 + n_blocks)
        raw = b""
        for size in sizes:
            raw += zlib.decompress(blob[at:at + size])
            at += size
        arrays[name] = np.frombuffer(raw, dtype=dtype)
    return arrays


def main():
    path = Path(sys.argv[1])
    frames = [path]
    if path.suffix == ".pvd":
        frames = [path.parent / f for f in re.findall(r'file="([^"]+)"', path.read_text())]
    sums = {}
    for frame in frames:
        arrays = read_arrays(frame)
        for name in arrays:
            if name.startswith("exact_"):
                out = name[len("exact_"):]
                e, x = arrays["error_" + out], arrays[name]
                s = sums.setdefault(out, [0.0, 0.0, 0.0])
                s[0] += float(e @ e)
                s[1] += float(x @ x)
                s[2] = max(s[2], float(np.abs(e).max()))
    for out, (ee, xx, mx) in sums.items():
        print("%s: rel_l2 %.3e, max_abs_err %.3e" % (out, np.sqrt(ee / xx), mx))


if __name__ == "__main__":
    main()
