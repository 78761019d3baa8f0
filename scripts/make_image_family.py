#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Makes data/images/family/: 64 x 64 grey crops of eleven pictures that Debian's
python3-skimage (0.19.3) ships, six per picture at seeded random places, for
configs/meta_images.yaml (issue 28). Crop 5 of eight of the pictures is held out; crops 0-4 of
those pictures that share pixels with it are not written. Run from the repository root with Debian's python:

    /usr/bin/python3 scripts/make_image_family.py

Each picture is made grey (skimage.color.rgb2gray for colour ones), shrunk by area averaging
by an integer factor so that its shorter side is about 192 pixels or more (so a crop holds a
recognisable part of it), and cropped; pixel values rounded to 8 bits. The origins and
licences: data/SOURCES.md.
"""
import os

import numpy as np
import skimage.color
import skimage.data
import skimage.io
from skimage.transform import downscale_local_mean

# Crop 5 of these is held out by configs/meta_images.yaml and latent_images.yaml.
HELD_OUT = ['camera', 'astronaut', 'chelsea', 'coffee', 'brick', 'rocket', 'clock', 'retina']
NAMES = ['camera', 'astronaut', 'chelsea', 'coffee', 'brick', 'grass', 'gravel', 'rocket',
         'retina', 'clock', 'hubble_deep_field']


def main():
    out = 'data/images/family'
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(28)
    for name in NAMES:
        image = getattr(skimage.data, name)()
        if image.ndim == 3:
            image = skimage.color.rgb2gray(image[..., :3]) * 255
        image = image.astype(np.float64)
        factor = max(1, int(min(image.shape) // 192))
        image = downscale_local_mean(image, (factor, factor))
        height, width = image.shape
        places = [(rng.integers(0, height - 64), rng.integers(0, width - 64)) for _ in range(6)]
        held_y, held_x = places[5]
        for k, (y, x) in enumerate(places):
            # No training crop may share pixels with a held-out one.
            if name in HELD_OUT and k < 5 and abs(y - held_y) < 64 and abs(x - held_x) < 64:
                continue
            crop = np.clip(np.round(image[y:y + 64, x:x + 64]), 0, 255).astype(np.uint8)
            skimage.io.imsave(f'{out}/{name.split("_")[0]}_{k}.png', crop, check_contrast=False)


if __name__ == '__main__':
    main()
