// SPDX-License-Identifier: MIT
//
// A 2-D grid's triangles clipped to a domain (marching triangles), for domain.vtu
// (domain_output.h).
//
// Triangles. Every cell (i, j) of the grid is split along its (i, j)–(i+1, j+1) diagonal into
// two triangles, counter-clockwise in (x, y). With the grid points' inside mask a triangle is
//   three corners inside:  kept as it is;
//   none inside:           dropped;
//   one inside (a):        the triangle (a, p_ab, p_ac);
//   two inside (a, b):     the quadrilateral (a, b, p_bc, p_ca), as two triangles,
// where p_ab is the crossing of ∂Ω on the edge from the inside corner a to the outside corner
// b. Each is counter-clockwise like the triangle it came from. A crossing belongs to its grid
// edge, not to the triangle: the two triangles beside an edge share one point, so the mesh is
// conforming (no cracks for ParaView's filters).
//
// Crossings by bisection on the exact inside test (Geometry::contains): the bracket [a, b]
// (a inside, b outside) is halved until it is shorter than `tolerance`, and the crossing is
// its inside end. So every point of the mesh is inside Ω (closed-set test), and a crossing
// lies within `tolerance` of ∂Ω along its edge (a corner a on ∂Ω is its own crossing, and
// the pieces that degenerate to no area are left out); a curved boundary is followed to that
// tolerance at the crossings and by chords between them, so the mesh's area differs from
// |Ω| by O(h²) (a chord of length h is O(h²/R) from an arc of radius R), corners of ∂Ω
// inside a triangle being cut off, O(h²) each. Where ∂Ω crosses one edge more than once
// (a feature thinner than a cell), bisection finds one crossing and the feature is lost at
// that resolution, as it is in the grid's mask.
//
// Why not VTK's clip (vtkTableBasedClipDataSet or vtkClipDataSet, with a scalar array of the
// signed distance ψ or an implicit function wrapping it): both place a crossing by linear
// interpolation of the scalar between the edge's ends, which is O(h²) off a curved boundary
// and off by more where ψ is an R-function join (not a distance: its level sets bend at the
// joins), and they interpolate the point data linearly too. The output wants the field
// evaluated at the crossing itself (u, grad_u, the residual, the error: a residual
// interpolated between grid points is no residual), so every new point would have to be
// re-placed and re-evaluated after VTK's filter; what remains of the filter, the case table,
// is the four lines above for triangles.
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "io/grid.h"

namespace nfield::solvers {

struct ClippedTriangles {
  Eigen::MatrixXd points;  // n × 2
  // Per point: its index in the grid (grid order), or −1 for a crossing.
  std::vector<Eigen::Index> grid_index;
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;  // counter-clockwise
  // The crossings' rows of `points`, in order (the rows with grid_index −1).
  std::vector<Eigen::Index> crossings() const;
};

// The triangles of a 2-D grid (dims[2] == 1) clipped to {contains}; `inside` is the grid
// points' mask (contains at each grid point, as the grid outputs have it), `tolerance` > 0
// the length at which a bisection stops.
ClippedTriangles clip_triangles(const io::Grid& grid, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside,
                                const std::function<bool(const Eigen::Vector2d&)>& contains, double tolerance);

// The tolerance domain.vtu uses: 10⁻⁶ of the grid's smaller spacing (20 bisections of an
// edge; well below what a picture or a plot of the mesh shows).
double clip_tolerance(const io::Grid& grid);

}  // namespace nfield::solvers
