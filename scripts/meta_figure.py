#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The guide's picture (docs/guide.md) of a meta-learning run (solvers/run/meta_run.h): for each held-out picture
(rows), the picture itself, then its fit after 0, K and C steps from the learned
initialisation and after 0, K and C steps from the standard one, and the standard one at the
step where it first matches the learned one's K-step figure; and beside it the mean held-out
curve of both (held_out_curve.csv).

    /usr/bin/python3 scripts/meta_figure.py out/meta_images docs/images/meta_images.png data/images/family

The third argument, optional, is the folder of the pictures themselves (the first column).

K and C are the run's inner_steps and curve_steps (from its config.yaml). Reads only the run's
own files; writes one PNG.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import skimage.io  # noqa: E402
import yaml  # noqa: E402


def main(run, out_png):
    config = yaml.safe_load(open(os.path.join(run, 'config.yaml')))
    metrics = json.load(open(os.path.join(run, 'metrics.json')))
    meta = config['training']['meta']
    k, c = meta['inner_steps'], meta['curve_steps']
    held = metrics['held_out']
    columns = ['picture', f'learned, 0', f'learned, {k}', f'learned, {c}', 'standard, 0', f'standard, {k}',
               f'standard, {c}', 'standard, match']
    fig = plt.figure(figsize=(2.0 * len(columns) + 4.5, 2.0 * len(held)))
    grid = fig.add_gridspec(len(held), len(columns) + 2)
    for row, item in enumerate(held):
        stem = os.path.splitext(item['name'])[0]
        base = os.path.join(run, 'held_out', stem)
        source = sys.argv[3] if len(sys.argv) > 3 else None
        picture = skimage.io.imread(os.path.join(source, item['name'])) if source else None
        cells = [picture] + [os.path.join(base, f'meta_{s}', 'reconstruction.png') for s in (0, k, c)] + \
                [os.path.join(base, f'standard_{s}', 'reconstruction.png') for s in (0, k, c)] + \
                [os.path.join(base, 'standard_match', 'reconstruction.png')]
        steps = item['standard_steps_to_match']
        for col, cell in enumerate(cells):
            ax = fig.add_subplot(grid[row, col])
            ax.set_xticks([])
            ax.set_yticks([])
            if isinstance(cell, str):
                cell = skimage.io.imread(cell) if os.path.exists(cell) else None
            if cell is not None:
                ax.imshow(cell, cmap='gray', vmin=0, vmax=255)
            title = columns[col] if col < 7 else (f'standard, {steps}' if steps else 'no match')
            if row == 0 or col == 7:
                ax.set_title(title, fontsize=9)
            if col == 0:
                ax.set_ylabel(stem, fontsize=9)
    rows = list(csv.DictReader(open(os.path.join(run, 'held_out_curve.csv'))))
    ax = fig.add_subplot(grid[:, len(columns):])
    meta_curve = [float(r['meta_mean']) for r in rows if r['meta_mean']]
    standard_curve = [float(r['standard_mean']) for r in rows if r['standard_mean']]
    ax.plot(range(len(standard_curve)), standard_curve, label='standard init (Adam)')
    ax.plot(range(len(meta_curve)), meta_curve, 'o-', label=f'learned init ({meta["inner_optimizer"]})')
    ax.axhline(metrics[f'held_out_meta_step{k}'], color='grey', lw=0.8, ls='--')
    ax.set_xscale('symlog', linthresh=1)
    ax.set_xlim(0, len(standard_curve))
    ax.set_xlabel('steps')
    ax.set_ylabel(f'held-out {metrics["held_out_figure"]} (mean)')
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png, dpi=56)


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
