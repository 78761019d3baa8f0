// SPDX-License-Identifier: MIT
//
// Outputs on the domain only, beside the grid's solution.vti, for a domain with a geometry
// (domain.geometry; solvers/geometry/geometry.h). grid_output.cc calls it once per frame.
//
// 2-D: domain.vtu, a VTK unstructured grid of triangles covering the domain: every cell of
//      the output grid is split into two triangles along its (i, j)–(i+1, j+1) diagonal, and
//      the triangles whose three corners are inside (Geometry::contains) are kept, with only
//      the points they use. No cut or clip: every kept point is a grid point, so its arrays
//      are the grid's values there, bit for bit (u, grad_u, the residual, exact_u and
//      error_u where there is a reference), and none lies outside. The price is a ragged
//      edge: the triangles stop up to one cell short of the boundary (a clip of ψ would reach
//      it, but with new points whose values are interpolated, not the field's). Refine
//      `output.grid` to close the gap.
// 3-D: boundary.vtp, the surface ψ = 0 of the geometry's distance sampled on the output grid
//      (flying edges, io/isosurface.h; its vertices lie on ∂Ω up to O(h²) of the grid spacing,
//      on the smooth zero set of a mesh's `distance: smooth`), with the field evaluated at its
//      vertices: u (each output by name), and exact_u and error_u where there is a reference.
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

namespace nfield::solvers {

// The triangles of a 2-D grid (dims[2] == 1) whose corners are all inside, and for each kept
// point its index in the grid (grid order).
struct InsideTriangles {
  std::vector<Eigen::Index> grid_index;
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;
};
InsideTriangles inside_triangles(const io::Grid& grid, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside);

class DomainOutput {
 public:
  // Arrays at points of ∂Ω (n × space dimension): the field there.
  using SurfaceArrays = std::function<io::PointArrays(const Eigen::MatrixXd&)>;

  // Writes nothing for a domain without a geometry. `series`: one file per frame and a .pvd.
  DomainOutput(const Domain& domain, const io::Grid& grid, std::filesystem::path dir, bool series);
  // Frame k at time t: `grid_arrays` are the grid's point arrays, `inside` its mask.
  void write(int k, double t, const io::PointArrays& grid_arrays, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside,
             const SurfaceArrays& surface);
  // The .pvd of a series.
  void finish() const;

 private:
  std::filesystem::path file(int k) const;

  const Domain& domain_;
  io::Grid grid_;
  std::filesystem::path dir_;
  bool series_;
  std::optional<io::PvdCollection> pvd_;
  std::optional<InsideTriangles> triangles_;  // 2-D, built on the first frame
  std::optional<io::TriangleMesh> surface_;   // 3-D, built on the first frame
};

}  // namespace nfield::solvers
