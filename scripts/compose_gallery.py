#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Makes the README's gallery pictures from the runs of scripts/make_gallery.sh.

    scripts/compose_gallery.py RUNS_DIR IMAGES_DIR

Each picture is scaled to a height of 256 pixels (nearest neighbour for pictures smaller
than that, so that the grid's cells stay visible as they are); the radiance field's test view
is put beside its ground truth.
"""
import pathlib
import sys

from PIL import Image

HEIGHT = 256


def scaled(path):
    image = Image.open(path).convert("RGB")
    width = max(1, round(image.width * HEIGHT / image.height))
    method = Image.NEAREST if image.height < HEIGHT else Image.LANCZOS
    return image.resize((width, HEIGHT), method)


def beside(left, right, gap=6):
    out = Image.new("RGB", (left.width + gap + right.width, HEIGHT), "white")
    out.paste(left, (0, 0))
    out.paste(right, (left.width + gap, 0))
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    runs, images = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    pictures = {
        "gallery_plate.png": scaled(runs / "poisson_plate_with_holes/solution.png"),
        "gallery_allen_cahn.png": scaled(runs / "allen_cahn_1d/solution.png"),
        "gallery_sdf.png": scaled(runs / "sdf_bunny/surface.png"),
        "gallery_nerf.png": beside(scaled(runs / "nerf_bunny_hash_grid/test_views/test_000_render.png"),
                                   scaled(runs / "nerf_bunny_hash_grid/test_views/test_000_truth.png")),
        "gallery_autoint.png": scaled(runs / "autoint_cos/integrand.png"),
    }
    images.mkdir(parents=True, exist_ok=True)
    for name, picture in pictures.items():
        picture.save(images / name, optimize=True)
        print(f"wrote {images / name} ({picture.width}×{picture.height})")


if __name__ == "__main__":
    main()
