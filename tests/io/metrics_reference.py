#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""io::psnr, io::ssim and io::compare_surfaces against independent implementations.

Images: scikit-image's peak_signal_noise_ratio and structural_similarity with the options
that are io/image_metrics.h's definition (data_range 1, gaussian_weights with sigma 1.5,
hence an 11 x 11 window, use_sample_covariance False, K1 0.01, K2 0.03, the mean over the
valid windows and the channels), on shipped images with Gaussian noise, blur and shifts.
They must agree to 1e-6 (absolute, PSNR in dB); both compute in double from the same float32
pixels, so they agree far closer.

Meshes: the Chamfer means and the normal consistency of pairs of shipped meshes against
SciPy's cKDTree on dense samples of each surface (every triangle subdivided n x n).
  - From the samples alone: a vertex's distance to the nearest sample is at least its
    distance to the surface (the samples lie on it) and at most that plus the largest
    distance from a point of a sub-triangle to its nearest corner, its longest edge / sqrt(3)
    (the circumradius of an acute triangle whose largest angle is at least 60 degrees; less
    for an obtuse one). So 0 <= samples' mean - nfield's mean <= that bound, which the
    subdivision (edges of at most 5e-3 of the diagonal) keeps below 2.9e-3 of it.
  - Exactly: the triangles of the k nearest samples are candidates, their exact distances
    (this file's own point-triangle distance) give the nearest; a candidate set is complete
    when the k-th sample lies farther than the nearest candidate plus the bound (any closer
    triangle has a sample within its distance plus the bound), else k grows. The Chamfer
    means then agree to 1e-9 of the diagonal, and the normal consistency must lie between
    the means of the smallest and largest |n . m| over the triangles tied for nearest
    (within 1e-9 of the diagonal: a vertex nearest to an edge or corner of the other surface
    has several, and the definition does not say which).

Exit codes: 0 agreement, 1 a disagreement, 77 (CTest's skip) when NumPy, SciPy or
scikit-image is missing.

Usage: metrics_reference.py METRICS_TOOL SOURCE_DIR SCRATCH_DIR
"""

import os
import subprocess
import sys

try:
    import numpy as np
    import scipy.ndimage
    from scipy.spatial import cKDTree
    import skimage
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity
except ImportError as exc:
    print(f"SKIP: {exc} (Debian: apt-get install python3-skimage python3-scipy)")
    sys.exit(77)

TOOL, SOURCE, SCRATCH = sys.argv[1:4]
IMAGE_TOLERANCE = 1e-6


def tool(*args):
    return subprocess.run([TOOL, *args], check=True, capture_output=True, text=True).stdout


def path(name):
    return os.path.join(SCRATCH, name)


# ------------------------------------------------------------------------ images
def image_pairs():
    """(name, reference, distorted) float32 arrays of shape (H, W, C)."""
    rng = np.random.default_rng(7)
    pairs = []
    for image in ("images/camera.png", "images/chelsea.png", "video/tree_001.png"):
        raw = path(os.path.basename(image) + ".f32")
        w, h, c = map(int, tool("png", os.path.join(SOURCE, "data", image), raw).split())
        x = np.fromfile(raw, dtype="<f4").reshape(h, w, c)
        stem = os.path.splitext(os.path.basename(image))[0]
        distortions = {
            "noise_0.02": x + rng.normal(0, 0.02, x.shape),
            "noise_0.1_clipped": np.clip(x + rng.normal(0, 0.1, x.shape), 0, 1),
            "blur_1": scipy.ndimage.gaussian_filter(x, (1, 1, 0)),
            "blur_3": scipy.ndimage.gaussian_filter(x, (3, 3, 0)),
            "shift_2.5_-1": scipy.ndimage.shift(x, (2.5, -1, 0), order=1, mode="nearest"),
            "shift_blur_noise": scipy.ndimage.shift(scipy.ndimage.gaussian_filter(x, (0.7, 0.7, 0)), (0, 1, 0),
                                                    order=0, mode="nearest") + rng.normal(0, 0.01, x.shape),
        }
        for kind, y in distortions.items():
            pairs.append((f"{stem}.{kind}", x, y.astype(np.float32)))
    return pairs


def check_images(manifest, results):
    pairs = image_pairs()
    for name, x, y in pairs:
        h, w, c = x.shape
        a, b = path(name + ".test.f32"), path(name + ".ref.f32")
        y.astype("<f4").tofile(a)
        x.astype("<f4").tofile(b)
        manifest.append(f"image {name} {w} {h} {c} {a} {b}")
    yield len(pairs)
    worst_psnr = worst_ssim = 0.0
    ok = True
    print(f"{'pair':34} {'nfield PSNR':>19} {'|diff|':>8} {'nfield SSIM':>19} {'|diff|':>8}")
    for name, x, y in pairs:
        # float64 copies of the same float32 values: skimage keeps float32 inputs in float32.
        ref, test = x.astype(np.float64), y.astype(np.float64)
        psnr = peak_signal_noise_ratio(ref, test, data_range=1.0)
        ssim = structural_similarity(ref, test, data_range=1.0, channel_axis=2, gaussian_weights=True,
                                     sigma=1.5, use_sample_covariance=False, K1=0.01, K2=0.03)
        got_psnr, got_ssim = results[("image", name)]
        dp, ds = abs(got_psnr - psnr), abs(got_ssim - ssim)
        worst_psnr, worst_ssim = max(worst_psnr, dp), max(worst_ssim, ds)
        bad = not (dp <= IMAGE_TOLERANCE and ds <= IMAGE_TOLERANCE)
        ok &= not bad
        print(f"{name:34} {got_psnr:19.12f} {dp:8.1e} {got_ssim:19.15f} {ds:8.1e}{'  FAIL' if bad else ''}")
    print(f"images: {len(pairs)} pairs, largest |PSNR diff| {worst_psnr:.2e} dB, largest |SSIM diff| "
          f"{worst_ssim:.2e} (tolerance {IMAGE_TOLERANCE:g}; scikit-image {skimage.__version__})")
    yield ok


# ------------------------------------------------------------------------ meshes
def read_mesh(prefix):
    v = np.fromfile(prefix + ".v.f64", dtype="<f8").reshape(-1, 3)
    t = np.fromfile(prefix + ".t.i32", dtype="<i4").reshape(-1, 3)
    return v, t


def write_mesh(prefix, v, t):
    v.astype("<f8").tofile(prefix + ".v.f64")
    t.astype("<i4").tofile(prefix + ".t.i32")


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = np.radians(degrees)
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def samples(v, t, spacing):
    """Points on every triangle at the barycentric grid i/n, j/n (n from its longest edge),
    the triangle of each, and the bound on the distance from a surface point to a sample."""
    e = np.stack([v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 1]], v[t[:, 0]] - v[t[:, 2]]], 1)
    longest = np.linalg.norm(e, axis=2).max(1)
    n = np.maximum(1, np.ceil(longest / spacing)).astype(int)
    points, owner = [], []
    for m in np.unique(n):
        tri = np.flatnonzero(n == m)
        i, j = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
        keep = i + j <= m
        u, w = i[keep] / m, j[keep] / m  # weights of corners 1 and 2
        a, b, c = v[t[tri, 0]], v[t[tri, 1]], v[t[tri, 2]]
        p = a[:, None] + u[None, :, None] * (b - a)[:, None] + w[None, :, None] * (c - a)[:, None]
        points.append(p.reshape(-1, 3))
        owner.append(np.repeat(tri, len(u)))
    bound = (longest / n).max() / np.sqrt(3)
    return np.concatenate(points), np.concatenate(owner), bound


def point_triangle_distance(p, a, b, c):
    """Distance of each point p[i] to the triangle (a[i], b[i], c[i]): the plane's distance
    where the projection falls inside, else the nearest of the three edges."""
    def segment(p, a, b):
        ab = b - a
        length2 = np.einsum("ij,ij->i", ab, ab)
        s = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.where(length2 > 0, length2, 1), 0, 1)
        return np.linalg.norm(p - (a + s[:, None] * ab), axis=1)

    normal = np.cross(b - a, c - a)
    norm2 = np.einsum("ij,ij->i", normal, normal)
    height = np.einsum("ij,ij->i", p - a, normal)
    q = p - (height / np.where(norm2 > 0, norm2, 1))[:, None] * normal
    inside = norm2 > 0
    for x, y in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(y - x, q - x), normal) >= 0
    edges = np.minimum(np.minimum(segment(p, a, b), segment(p, b, c)), segment(p, c, a))
    plane = np.abs(height) / np.sqrt(np.where(norm2 > 0, norm2, 1))
    return np.where(inside, plane, edges)


def unit(x):
    norm = np.linalg.norm(x, axis=1, keepdims=True)
    return np.where(norm > 0, x / np.where(norm > 0, norm, 1), 0)


def one_way(va, ta, vb, tb, spacing, tie):
    """Vertices of a to surface b: the samples' mean distance, its bound, the exact mean, and
    the smallest and largest mean |n . m| over the tied nearest triangles."""
    used = np.unique(ta)
    p = va[used]
    cross = np.cross(va[ta[:, 1]] - va[ta[:, 0]], va[ta[:, 2]] - va[ta[:, 0]])
    vertex_normals = np.zeros_like(va)
    for k in range(3):  # area-weighted: the cross product is twice the area times the normal
        np.add.at(vertex_normals, ta[:, k], cross)
    n_a = unit(vertex_normals[used])
    m_b = unit(np.cross(vb[tb[:, 1]] - vb[tb[:, 0]], vb[tb[:, 2]] - vb[tb[:, 0]]))

    points, owner, bound = samples(vb, tb, spacing)
    tree = cKDTree(points)
    nearest, _ = tree.query(p, k=1)
    exact = np.empty(len(p))
    low, high = np.empty(len(p)), np.empty(len(p))
    todo, k = np.arange(len(p)), 16
    while len(todo):
        dk, idx = tree.query(p[todo], k=k)
        cand = owner[idx]  # (rows, k) triangle ids
        rows = np.repeat(np.arange(len(todo)), k)
        tri = cand.ravel()
        d = point_triangle_distance(p[todo][rows], vb[tb[tri, 0]], vb[tb[tri, 1]], vb[tb[tri, 2]]).reshape(-1, k)
        best = d.min(1)
        complete = dk[:, -1] > best + bound
        align = np.abs(np.einsum("ij,ikj->ik", n_a[todo], m_b[cand]))
        tied = d <= best[:, None] + tie
        done = todo[complete]
        exact[done] = best[complete]
        low[done] = np.where(tied, align, np.inf).min(1)[complete]
        high[done] = np.where(tied, align, -np.inf).max(1)[complete]
        todo, k = todo[~complete], 4 * k
    return nearest.mean(), bound, exact.mean(), low.mean(), high.mean()


def mesh_pairs():
    dumped = {}
    for name in ("sphere", "bunny00"):
        prefix = path(name)
        tool("mesh", os.path.join(SOURCE, "data", "meshes", name + ".ply"), prefix)
        dumped[name] = read_mesh(prefix)
    sv, st = dumped["sphere"]
    bv, bt = dumped["bunny00"]
    sc, bc = sv.mean(0), bv.mean(0)
    b_diag = np.linalg.norm(bv.max(0) - bv.min(0))
    s_diag = np.linalg.norm(sv.max(0) - sv.min(0))
    return [
        # The sphere against itself turned and 10 % larger: no vertex of one lies on the other.
        ("sphere_turned_larger", "sphere", (sv - sc) @ rotation((1, 2, 3), 17).T * 1.1 + sc, st),
        # The bunny against itself turned by 3 degrees and moved by 1 % of its diagonal.
        ("bunny_moved", "bunny00", (bv - bc) @ rotation((0.3, 1, 0.2), 3).T + bc + 0.01 * b_diag * np.array([0.6, -0.48, 0.64]), bt),
        # Unrelated surfaces: the sphere scaled into the bunny's box.
        ("sphere_in_bunny", "bunny00", (sv - sc) * (0.7 * b_diag / s_diag) + bc, st),
    ], dumped


def check_meshes(manifest, results):
    pairs, dumped = mesh_pairs()
    for name, a_name, v, t in pairs:
        write_mesh(path(name), v, t)
        manifest.append(f"mesh {name} {path(a_name)} {path(name)}")
    yield len(pairs)
    ok = True
    for name, a_name, vb, tb in pairs:
        va, ta = dumped[a_name]
        diagonal = np.linalg.norm(np.vstack([va, vb]).max(0) - np.vstack([va, vb]).min(0))
        spacing, tie = 5e-3 * diagonal, 1e-9 * diagonal
        got_ab, got_ba, got_nc = results[("mesh", name)]
        ab = one_way(va, ta, vb, tb, spacing, tie)
        ba = one_way(vb, tb, va, ta, spacing, tie)
        print(f"{name}: diagonal {diagonal:.4g}")
        for label, got, (sampled, bound, exact, _, _) in (("a_to_b", got_ab, ab), ("b_to_a", got_ba, ba)):
            gap = sampled - got
            good_samples = -1e-12 * diagonal <= gap <= bound
            good_exact = abs(exact - got) <= 1e-9 * diagonal
            ok &= good_samples and good_exact
            print(f"  chamfer {label}: nfield {got:.12g}; samples {sampled:.12g} (- nfield = {gap:.3g}, "
                  f"in [0, {bound:.3g}]: {'yes' if good_samples else 'NO'}); exact {exact:.12g} "
                  f"(|diff| {abs(exact - got):.2g}, <= {1e-9 * diagonal:.2g}: {'yes' if good_exact else 'NO'})")
        low, high = 0.5 * (ab[3] + ba[3]), 0.5 * (ab[4] + ba[4])
        good_nc = low - 1e-12 <= got_nc <= high + 1e-12
        ok &= good_nc
        print(f"  normal consistency: nfield {got_nc:.12g}, over the tied nearest triangles "
              f"[{low:.12g}, {high:.12g}]: {'yes' if good_nc else 'NO'}")
    yield ok


def main():
    os.makedirs(SCRATCH, exist_ok=True)
    manifest, results = [], {}
    # Each check writes its inputs and manifest lines, then (after the one run of the tool,
    # which fills `results`) compares.
    checks = [check_images(manifest, results), check_meshes(manifest, results)]
    for check in checks:
        next(check)
    with open(path("manifest.txt"), "w") as fh:
        fh.write("\n".join(manifest) + "\n")
    for line in tool("compare", path("manifest.txt")).splitlines():
        words = line.split()
        results[(words[0], words[1])] = tuple(float(x) for x in words[2:])
    ok = True
    for check in checks:
        ok &= next(check)
    print("agree" if ok else "DISAGREE")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
