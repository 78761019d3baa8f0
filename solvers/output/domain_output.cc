// SPDX-License-Identifier: MIT
#include "solvers/output/domain_output.h"

#include <array>
#include <cstdio>
#include <vector>

#include "io/isosurface.h"
#include "io/vtk_polydata.h"
#include "solvers/geometry/geometry.h"

namespace nfield::solvers {

InsideTriangles inside_triangles(const io::Grid& grid, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside) {
  const int nx = grid.dims[0], ny = grid.dims[1];
  std::vector<int> id(static_cast<size_t>(grid.point_count()), -1);
  InsideTriangles out;
  std::vector<std::array<int, 3>> tris;
  const auto use = [&](Eigen::Index g) {
    int& i = id[static_cast<size_t>(g)];
    if (i < 0) {
      i = static_cast<int>(out.grid_index.size());
      out.grid_index.push_back(g);
    }
    return i;
  };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const Eigen::Index a = i + static_cast<Eigen::Index>(nx) * j, b = a + 1, c = a + nx + 1, d = a + nx;
      // Counter-clockwise in (x, y): (a, b, c) and (a, c, d).
      for (const auto& t : {std::array<Eigen::Index, 3>{a, b, c}, std::array<Eigen::Index, 3>{a, c, d}})
        if (inside(t[0]) && inside(t[1]) && inside(t[2])) tris.push_back({use(t[0]), use(t[1]), use(t[2])});
    }
  out.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t k = 0; k < tris.size(); ++k)
    for (int c = 0; c < 3; ++c) out.triangles(static_cast<Eigen::Index>(k), c) = tris[k][static_cast<size_t>(c)];
  return out;
}

DomainOutput::DomainOutput(const Domain& domain, const io::Grid& grid, std::filesystem::path dir, bool series)
    : domain_(domain), grid_(grid), dir_(std::move(dir)), series_(series) {
  if (series_ && domain_.geometry())
    pvd_.emplace(dir_ / (domain_.space_dim() == 2 ? "domain.pvd" : "boundary.pvd"));
}

std::filesystem::path DomainOutput::file(int k) const {
  const bool flat = domain_.space_dim() == 2;
  if (!series_) return flat ? "domain.vtu" : "boundary.vtp";
  char name[64];
  std::snprintf(name, sizeof name, flat ? "domain_%04d.vtu" : "boundary_%04d.vtp", k);
  return name;
}

void DomainOutput::write(int k, double t, const io::PointArrays& grid_arrays,
                         const Eigen::Array<bool, Eigen::Dynamic, 1>& inside, const SurfaceArrays& surface) {
  const geometry::Geometry* g = domain_.geometry();
  if (!g) return;
  const std::filesystem::path name = file(k);
  if (domain_.space_dim() == 2) {
    if (!triangles_) triangles_ = inside_triangles(grid_, inside);
    io::TriangleGrid data;
    const Eigen::Index n = static_cast<Eigen::Index>(triangles_->grid_index.size());
    data.points.resize(n, 3);
    for (Eigen::Index p = 0; p < n; ++p) data.points.row(p) = grid_.point(triangles_->grid_index[static_cast<size_t>(p)]).transpose();
    data.triangles = triangles_->triangles;
    for (const auto& [key, m] : grid_arrays) {
      if (key == "inside") continue;  // 1 at every kept point
      Eigen::MatrixXd rows(n, m.cols());
      for (Eigen::Index p = 0; p < n; ++p) rows.row(p) = m.row(triangles_->grid_index[static_cast<size_t>(p)]);
      data.arrays[key] = std::move(rows);
    }
    io::write_vtu(dir_ / name, data);
  } else {
    if (!surface_) {
      // −ψ, negative inside, so that the triangles face outward (io/isosurface.h).
      Eigen::VectorXd minus_psi(grid_.point_count());
      for (Eigen::Index p = 0; p < minus_psi.size(); ++p) minus_psi(p) = -g->distance(grid_.point(p)).v;
      surface_ = io::extract_isosurface(grid_, minus_psi, 0.0, true);
    }
    io::PointArrays arrays = surface_->vertices.rows() ? surface(surface_->vertices) : io::PointArrays{};
    io::write_vtp_mesh(dir_ / name, *surface_, arrays);
  }
  if (pvd_) {
    pvd_->add(t, name.string());
  }
}

void DomainOutput::finish() const {
  if (pvd_) pvd_->write();
}

}  // namespace nfield::solvers
