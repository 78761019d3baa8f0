#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Draws an acorn run's blocks over its reconstruction: the leaves of the block tree in
checkpoint.h5 (field attributes acorn_block_level / acorn_block_index, fields/acorn_type.cc)
as outlines, brighter for finer levels, on reconstruction.png beside the original picture.

Usage: plot_acorn_blocks.py RUN_DIR OUT.png [--width N]   (an image fit of a 2-D acorn field)
--width N: first shrink the picture to about N pixels across (area averaging by an integer
factor), so that the outlines of a large picture's blocks stay visible.
"""
import argparse

import h5py
import numpy as np
from skimage import io


def shrink(picture, width):
    factor = max(1, picture.shape[1] // width)
    h, w = (picture.shape[0] // factor) * factor, (picture.shape[1] // factor) * factor
    return picture[:h, :w].reshape(h // factor, factor, w // factor, factor).mean(axis=(1, 3))


def main(run_dir, out, width=None):
    with h5py.File(f"{run_dir}/checkpoint.h5", "r") as f:
        levels = np.asarray(f["field"].attrs["acorn_block_level"])
        index = np.asarray(f["field"].attrs["acorn_block_index"]).reshape(-1, 2)
    picture = io.imread(f"{run_dir}/reconstruction.png").astype(float) / 255
    if picture.ndim == 3:
        picture = picture[..., :3].mean(axis=2)
    if width:
        picture = shrink(picture, width)
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
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir")
    parser.add_argument("out")
    parser.add_argument("--width", type=int, default=None)
    args = parser.parse_args()
    main(args.run_dir, args.out, args.width)
