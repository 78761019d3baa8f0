// SPDX-License-Identifier: MIT
//
// Outputs on the domain only, beside the grid's solution.vti, for a domain with a geometry
// (domain.geometry; solvers/geometry/geometry.h). grid_output.cc calls it once per frame.
//
// 2-D: domain.vtu, a VTK unstructured grid of triangles covering the domain: the output
//      grid's triangles clipped to ∂Ω (marching triangles with crossings found by bisection
//      on the exact inside test, domain_clip.h), so the mesh reaches the boundary (within
//      10⁻⁶ of a cell, every point inside) and its area is |Ω| up to O(h²). At the grid points
//      the arrays are the grid's values, bit for bit; at the crossings the field is evaluated
//      there (the same arrays: u, grad_u, the residual, exact_u and error_u where there is a
//      reference), not interpolated.
// 3-D: boundary.vtp, the surface ψ = 0 of the geometry's distance sampled on the output grid
//      (flying edges, io/isosurface.h; its vertices lie on ∂Ω up to O(h²) of the grid spacing,
//      on the smooth zero set of a mesh's `distance: smooth`), with the field evaluated at its
//      vertices: the grid's arrays (u, grad_u, the residual, exact_u and error_u).
//      solution.vti's `inside` mask shows the volume.
// Time series: domain_0000.vtu … (boundary_0000.vtp …) with domain.pvd (boundary.pvd).
#pragma once

#include <filesystem>
#include <functional>
#include <optional>

#include "io/grid.h"
#include "io/point_arrays.h"
#include "io/pvd.h"
#include "io/triangle_mesh.h"
#include "io/vtk_unstructured.h"
#include "solvers/core/domain.h"
#include "solvers/output/domain_clip.h"

namespace nfield::solvers {

class DomainOutput {
 public:
  // The arrays a grid point has (the same names), at other points of the frame (n × space
  // dimension, all inside or on ∂Ω).
  using ArraysAt = std::function<io::PointArrays(const Eigen::MatrixXd&)>;

  // Writes nothing for a domain without a geometry. `series`: one file per frame and a .pvd.
  DomainOutput(const Domain& domain, const io::Grid& grid, std::filesystem::path dir, bool series);
  // Frame k at time t: `grid_arrays` are the grid's point arrays, `inside` its mask.
  void write(int k, double t, const io::PointArrays& grid_arrays, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside,
             const ArraysAt& at);
  // The .pvd of a series.
  void finish() const;

 private:
  std::filesystem::path file(int k) const;

  const Domain& domain_;
  io::Grid grid_;
  std::filesystem::path dir_;
  bool series_;
  std::optional<io::PvdCollection> pvd_;
  std::optional<ClippedTriangles> triangles_;  // 2-D, built on the first frame
  std::optional<io::TriangleMesh> surface_;   // 3-D, built on the first frame
};

}  // namespace nfield::solvers
