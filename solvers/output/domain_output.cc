// SPDX-License-Identifier: MIT
#include "solvers/output/domain_output.h"

#include <array>
#include <cstdio>
#include <limits>
#include <vector>

#include "io/isosurface.h"
#include "io/vtk_polydata.h"
#include "solvers/geometry/geometry.h"

namespace nfield::solvers {

namespace {

// Rows of `m` at the grid points, then `extra`'s rows (NaN when `extra` lacks the array).
Eigen::MatrixXd gather(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& grid_index,
                       const Eigen::MatrixXd* extra) {
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(grid_index.size()), m.cols());
  Eigen::Index k = 0;
  for (size_t p = 0; p < grid_index.size(); ++p) {
    const Eigen::Index g = grid_index[p];
    if (g >= 0) rows.row(static_cast<Eigen::Index>(p)) = m.row(g);
    else if (extra && extra->cols() == m.cols()) rows.row(static_cast<Eigen::Index>(p)) = extra->row(k++);
    else rows.row(static_cast<Eigen::Index>(p)).setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return rows;
}

}  // namespace

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
                         const Eigen::Array<bool, Eigen::Dynamic, 1>& inside, const ArraysAt& at) {
  const geometry::Geometry* g = domain_.geometry();
  if (!g) return;
  const std::filesystem::path name = file(k);
  if (domain_.space_dim() == 2) {
    if (!triangles_)
      triangles_ = clip_triangles(
          grid_, inside, [g](const Eigen::Vector2d& p) { return g->contains(Eigen::Vector3d(p(0), p(1), 0)); },
          clip_tolerance(grid_));
    const std::vector<Eigen::Index> crossings = triangles_->crossings();
    Eigen::MatrixXd crossing_points(static_cast<Eigen::Index>(crossings.size()), 2);
    for (size_t c = 0; c < crossings.size(); ++c)
      crossing_points.row(static_cast<Eigen::Index>(c)) = triangles_->points.row(crossings[c]);
    const io::PointArrays extra = crossings.empty() ? io::PointArrays{} : at(crossing_points);
    io::TriangleGrid data;
    data.points = triangles_->points;
    data.triangles = triangles_->triangles;
    for (const auto& [key, m] : grid_arrays) {
      if (key == "inside") continue;  // 1 at every point
      const auto e = extra.find(key);
      data.arrays[key] = gather(m, triangles_->grid_index, e == extra.end() ? nullptr : &e->second);
    }
    io::write_vtu(dir_ / name, data);
  } else {
    if (!surface_) {
      // −ψ, negative inside, so that the triangles face outward (io/isosurface.h).
      Eigen::VectorXd minus_psi(grid_.point_count());
      for (Eigen::Index p = 0; p < minus_psi.size(); ++p) minus_psi(p) = -g->distance(grid_.point(p)).v;
      surface_ = io::extract_isosurface(grid_, minus_psi, 0.0, true);
    }
    io::PointArrays arrays = surface_->vertices.rows() ? at(surface_->vertices) : io::PointArrays{};
    arrays.erase("inside");
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
