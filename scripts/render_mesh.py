#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Renders a triangle mesh (a PLY that nfield writes: surface.ply) to a shaded PNG.

Orthographic view from a direction given by azimuth and elevation, Lambert shading with one
light at the camera, a z-buffer per pixel. NumPy and Pillow only: the gallery script
(scripts/make_gallery.sh) needs no OpenGL context.

    scripts/render_mesh.py MESH.ply OUT.png [--size 512] [--azimuth 30] [--elevation 20]
"""
import argparse
import sys

import numpy as np
from PIL import Image

PLY_TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8", "uchar": "u1",
             "uint8": "u1", "char": "i1", "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
             "short": "<i2", "ushort": "<u2"}


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header and "format ascii 1.0" not in header:
        sys.exit(f"{path}: only binary little-endian and ASCII PLY files are read")
    ascii_format = "format ascii 1.0" in header
    elements, current = [], None
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            current = {"name": words[1], "count": int(words[2]), "props": []}
            elements.append(current)
        elif words[:1] == ["property"]:
            current["props"].append(words[1:])
    body = data[end:]
    vertices = faces = None
    if ascii_format:
        rows = iter(body.decode("ascii").split("\n"))
        for element in elements:
            values = [next(rows).split() for _ in range(element["count"])]
            if element["name"] == "vertex":
                vertices = np.array([[float(v) for v in row[:3]] for row in values])
            elif element["name"] == "face":
                faces = np.array([[int(v) for v in row[1:4]] for row in values])
        return vertices, faces
    offset = 0
    for element in elements:
        props = element["props"]
        if element["name"] == "face":
            count_type, index_type = PLY_TYPES[props[0][1]], PLY_TYPES[props[0][2]]
            record = np.dtype([("n", count_type), ("i", index_type, (3,))])
            table = np.frombuffer(body, record, element["count"], offset)
            if np.any(table["n"] != 3):
                sys.exit(f"{path}: only triangles are read")
            faces = table["i"].astype(np.int64)
            offset += record.itemsize * element["count"]
        else:
            record = np.dtype([(p[1], PLY_TYPES[p[0]]) for p in props])
            table = np.frombuffer(body, record, element["count"], offset)
            offset += record.itemsize * element["count"]
            if element["name"] == "vertex":
                vertices = np.stack([table["x"], table["y"], table["z"]], axis=1).astype(np.float64)
    return vertices, faces


def render(vertices, faces, size, azimuth, elevation):
    a, e = np.radians(azimuth), np.radians(elevation)
    # Camera axes: right, up, towards the viewer (y up in the mesh's frame).
    toward = np.array([np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)])
    right = np.cross([0.0, 1.0, 0.0], toward)
    right /= np.linalg.norm(right)
    up = np.cross(toward, right)
    centred = vertices - 0.5 * (vertices.max(0) + vertices.min(0))
    view = centred @ np.stack([right, up, toward], axis=1)
    scale = 0.45 * size / np.abs(view[:, :2]).max()
    px = view[:, 0] * scale + size / 2
    py = size / 2 - view[:, 1] * scale
    depth = view[:, 2]
    tri = faces
    normals = np.cross(centred[tri[:, 1]] - centred[tri[:, 0]], centred[tri[:, 2]] - centred[tri[:, 0]])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    shade = np.abs(normals @ toward)
    zbuffer = np.full((size, size), -np.inf)
    image = np.full((size, size), np.nan)
    for k in np.argsort(depth[tri].mean(1)):
        i0, i1, i2 = tri[k]
        xs, ys = px[[i0, i1, i2]], py[[i0, i1, i2]]
        x_lo, x_hi = max(int(np.floor(xs.min())), 0), min(int(np.ceil(xs.max())), size - 1)
        y_lo, y_hi = max(int(np.floor(ys.min())), 0), min(int(np.ceil(ys.max())), size - 1)
        if x_lo > x_hi or y_lo > y_hi:
            continue
        gx, gy = np.meshgrid(np.arange(x_lo, x_hi + 1) + 0.5, np.arange(y_lo, y_hi + 1) + 0.5)
        det = (ys[1] - ys[2]) * (xs[0] - xs[2]) + (xs[2] - xs[1]) * (ys[0] - ys[2])
        if abs(det) < 1e-12:
            continue
        w0 = ((ys[1] - ys[2]) * (gx - xs[2]) + (xs[2] - xs[1]) * (gy - ys[2])) / det
        w1 = ((ys[2] - ys[0]) * (gx - xs[2]) + (xs[0] - xs[2]) * (gy - ys[2])) / det
        w2 = 1 - w0 - w1
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        z = w0 * depth[i0] + w1 * depth[i1] + w2 * depth[i2]
        block = zbuffer[y_lo:y_hi + 1, x_lo:x_hi + 1]
        nearer = inside & (z > block)
        block[nearer] = z[nearer]
        image[y_lo:y_hi + 1, x_lo:x_hi + 1][nearer] = shade[k]
    rgb = np.empty((size, size, 3))
    base = np.array([0.85, 0.72, 0.55])
    lit = np.nan_to_num(image, nan=0.0)[..., None] * 0.8 + 0.2
    rgb[:] = base * lit
    rgb[np.isnan(image)] = 1.0
    return (np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh")
    parser.add_argument("out")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--azimuth", type=float, default=30)
    parser.add_argument("--elevation", type=float, default=20)
    args = parser.parse_args()
    vertices, faces = read_ply(args.mesh)
    if vertices is None or faces is None or len(faces) == 0:
        sys.exit(f"{args.mesh}: no triangles")
    Image.fromarray(render(vertices, faces, args.size, args.azimuth, args.elevation)).save(args.out)
    print(f"wrote {args.out} ({len(faces)} triangles)")


if __name__ == "__main__":
    main()
