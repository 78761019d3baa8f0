#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Draws an acorn run's blocks over its reconstruction: the leaves of the block tree in
checkpoint.h5 (field attributes acorn_block_level / acorn_block_index, fields/acorn_type.cc)
as outlines, brighter for finer levels, on reconstruction.png beside the original picture.

Usage: plot_acorn_blocks.py RUN_DIR OUT.png   (an image fit of a 2-D acorn field)
"""
import sys

import h5py
import numpy as np
from skimage import io


def main(run_dir, out):
    with h5py.File(f"{run_dir}/checkpoint.h5", "r") as f:
        levels = np.asarray(f["field"].attrs["acorn_block_level"])
        index = np.asarray(f["field"].attrs["acorn_block_index"]).reshape(-1, 2)
    picture = io.imread(f"{run_dir}/reconstruction.png").astype(float) / 255
    if picture.ndim == 3:
        picture = picture[..., :3].mean(axis=2)
    h, w = picture.shape
    rgb = np.stack([picture] * 3, axis=2) * 0.8
    top = levels.max()
    for level, (i, j) in zip(levels, index):
        size = 2.0 ** -level
        # x right over columns; y up, so row 0 is the top (y = 1) edge.
        c0, c1 = int(round(i * size * w)), int(round((i + 1) * size * w)) - 1
        r0, r1 = int(round((1 - (j + 1) * size) * h)), int(round((1 - j * size) * h)) - 1
        colour = np.array([1.0, 0.3 + 0.7 * level / max(top, 1), 0.0])
        rgb[r0, c0:c1 + 1] = colour
        rgb[r1, c0:c1 + 1] = colour
        rgb[r0:r1 + 1, c0] = colour
        rgb[r0:r1 + 1, c1] = colour
    io.imsave(out, (np.clip(rgb, 0, 1) * 255).astype(np.uint8), check_contrast=False)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
