#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Draws the figure of NeRF in the Wild's protocol on the recoloured bunny
(configs/nerf_bunny_appearance.yaml against configs/nerf_bunny_recoloured.yaml).

One row per test view: the recoloured photograph, the plain NeRF's render, and the render
with an appearance code fitted to the photograph's left half (the dashed line; both scored on
the right half). A last row: the first training view rendered with the codes between the
first two training images' (interpolation/S/).

    scripts/appearance_figure.py APPEARANCE_DIR PLAIN_DIR FIGURE.png [--views 0 3 7]
"""
import argparse
import json
import math
import os

import numpy as np
from PIL import Image, ImageDraw

LABEL = 16


def right_half_psnr(render, truth):
    """PSNR of the right halves of two PNGs (8-bit: within about 0.1 dB of metrics.json)."""
    a = np.asarray(Image.open(render).convert("RGB"), dtype=np.float64) / 255
    b = np.asarray(Image.open(truth).convert("RGB"), dtype=np.float64) / 255
    half = a.shape[1] // 2
    return -10 * math.log10(max(np.mean((a[:, half:] - b[:, half:]) ** 2), 1e-20))


def labelled(path, label, dashed=False):
    image = Image.open(path).convert("RGB")
    tile = Image.new("RGB", (image.width, image.height + LABEL), "white")
    tile.paste(image, (0, 0))
    draw = ImageDraw.Draw(tile)
    if dashed:
        x = image.width // 2
        for y in range(0, image.height, 6):
            draw.line([(x, y), (x, min(y + 3, image.height - 1))], fill=(200, 0, 0))
    draw.text((3, image.height + 2), label, fill="black")
    return tile


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("appearance")
    parser.add_argument("plain")
    parser.add_argument("figure")
    parser.add_argument("--views", type=int, nargs="+", default=[0, 3, 7])
    args = parser.parse_args()
    with open(os.path.join(args.appearance, "metrics.json")) as f:
        held_out = {h["name"]: h for h in json.load(f)["held_out"]}
    names = sorted(held_out)
    rows = []
    for v in args.views:
        name = names[v]
        stem = os.path.splitext(name)[0]
        view = os.path.join(args.appearance, "held_out", stem, "view", "test_000_")
        plain = os.path.join(args.plain, "test_views", f"test_{v:03d}_render.png")
        rows.append([
            labelled(view + "truth.png", f"{stem}: photograph", dashed=True),
            labelled(plain, f"plain NeRF: {right_half_psnr(plain, view + 'truth.png'):.1f} dB"),
            labelled(view + "render.png", f"code fitted: {held_out[name]['psnr_right_half_mean']:.1f} dB", dashed=True),
        ])
    steps = sorted(int(s) for s in os.listdir(os.path.join(args.appearance, "interpolation")))
    rows.append([labelled(os.path.join(args.appearance, "interpolation", str(s), "view", "test_000_render.png"),
                          f"t = {s / (len(steps) - 1):.2f}") for s in steps])
    width = max(sum(t.width for t in row) for row in rows)
    height = sum(max(t.height for t in row) for row in rows)
    figure = Image.new("RGB", (width, height), "white")
    y = 0
    for row in rows:
        x = 0
        for t in row:
            figure.paste(t, (x, y))
            x += t.width
        y += max(t.height for t in row)
    figure.save(args.figure)


if __name__ == "__main__":
    main()
