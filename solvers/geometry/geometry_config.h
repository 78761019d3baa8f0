// SPDX-License-Identifier: MIT
//
// `domain.geometry` in a config: one shape, or a tree of them. Every node is a mapping with
// `shape:` and its own keys, plus any of `translate: [dx, dy(, dz)]`, `rotate:` (2-D: degrees
// about z; 3-D: [rx, ry, rz] degrees about x, then y, then z) and `scale:` (a positive number,
// uniform: a similarity keeps distances, normals and uniform sampling exact), applied in the
// order scale, rotate, translate. Primitives take `name:` (the part name of their boundary;
// default the shape and its number in depth-first order, `disk2`).
//
//   box        lower, upper               (2 or 3 numbers each; upper > lower)
//   disk       center [x, y], radius
//   ball       center [x, y, z], radius
//   ellipse    center, semi_axes          (2-D);  ellipsoid: the same in 3-D
//   polygon    vertices [[x, y], …] (≥ 3, edges must not cross), or file (`x y` lines)
//   cylinder   center, radius, height     (3-D, axis z: rotate it for another axis)
//   capsule    from, to, radius           (the points within radius of the segment)
//   mesh       file                       (3-D: .stl, .obj, .ply, .vtp, .off; a closed surface)
//   union, intersection, difference       shapes: [two or more nodes]; a difference removes
//                                         the second and later from the first
//
// Files are relative to the config's folder. Every error is an io::ConfigError at the key it
// concerns: a size that is zero or negative, a polygon with fewer than three vertices or
// crossing edges (the edges named), a mesh file that is missing, unreadable, open or
// self-intersecting (the reader's or checker's message), shapes of different dimensions, two
// parts with one name, and an empty domain (no point of 2¹⁴ drawn in the bounding box lies
// inside: a difference that removes everything, an intersection of disjoint shapes).
#pragma once

#include <filesystem>

#include "io/config.h"
#include "solvers/geometry/geometry.h"

namespace nfield::solvers::geometry {

Geometry read_geometry(const io::ConfigNode& node, const std::filesystem::path& config_dir);

// A selection of boundary parts from a condition's mapping: `on:` a part name, a list of them
// or `boundary`, and an optional `where:` expression over x, y(, z). An unknown name or a bad
// expression is a ConfigError at its key.
Selection read_selection(const io::ConfigNode& node, const Geometry& geometry);

}  // namespace nfield::solvers::geometry
