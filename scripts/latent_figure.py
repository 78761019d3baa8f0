#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Draws the figure of an auto-decoder run over shapes (configs/deepsdf_meshes.yaml).

Top row: each training shape's zero level set with its own code, then the held-out shapes
fitted by their codes alone. Bottom row: the surfaces along the line between the first two
training codes (interpolation/S/). Each surface is rendered by scripts/render_mesh.py's
shaded orthographic view; labels under each picture.

    scripts/latent_figure.py OUT_DIR FIGURE.png [--size 192]
"""
import argparse
import json
import os
import sys

from PIL import Image, ImageDraw

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from render_mesh import read_ply, render  # noqa: E402


def tile(path, size, label):
    vertices, faces = read_ply(path)
    picture = Image.new("RGB", (size, size + 18), "white")
    if vertices is not None and faces is not None and len(faces) > 0:
        picture.paste(Image.fromarray(render(vertices, faces, size, 30, 20)), (0, 0))
    ImageDraw.Draw(picture).text((4, size + 3), label, fill="black")
    return picture


def row(tiles, gap=4):
    width = sum(t.width for t in tiles) + gap * (len(tiles) - 1)
    out = Image.new("RGB", (width, max(t.height for t in tiles)), "white")
    x = 0
    for t in tiles:
        out.paste(t, (x, 0))
        x += t.width + gap
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="the output folder of the run")
    parser.add_argument("figure")
    parser.add_argument("--size", type=int, default=192)
    args = parser.parse_args()
    metrics_path = os.path.join(args.run, "metrics.json")
    if not os.path.exists(metrics_path):
        sys.exit(f"{metrics_path}: no such file (run the config first)")
    metrics = json.load(open(metrics_path))
    top = []
    for group, folder, suffix in (("training", "training", ""), ("held_out", "held_out", " (held out)")):
        for item in metrics.get(group, []):
            stem = os.path.splitext(item["name"])[0]
            chamfer = item.get("chamfer_mean_per_diagonal")
            label = f"{stem}{suffix}" + (f" {chamfer:.1e}" if chamfer is not None else "")
            top.append(tile(os.path.join(args.run, folder, stem, "surface.ply"), args.size, label))
    steps = sorted(int(d) for d in os.listdir(os.path.join(args.run, "interpolation")) if d.isdigit())
    bottom = [tile(os.path.join(args.run, "interpolation", str(s), "surface.ply"), args.size,
                   f"t = {s / (len(steps) - 1):.2f}") for s in steps]
    first, second = row(top), row(bottom)
    figure = Image.new("RGB", (max(first.width, second.width), first.height + second.height + 8), "white")
    figure.paste(first, (0, 0))
    figure.paste(second, (0, first.height + 8))
    figure.save(args.figure)
    print(f"wrote {args.figure}")


if __name__ == "__main__":
    main()
