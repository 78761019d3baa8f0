// SPDX-License-Identifier: MIT
#include "io/grid.h"

#include <stdexcept>
#include <string>

namespace nfield::io {

Eigen::Index Grid::point_count() const { return Eigen::Index{dims[0]} * dims[1] * dims[2]; }

int Grid::dimension() const { return (dims[0] > 1) + (dims[1] > 1) + (dims[2] > 1); }

Eigen::Vector3d Grid::point(Eigen::Index index) const {
  const Eigen::Index i = index % dims[0], jk = index / dims[0];
  const Eigen::Index j = jk % dims[1], k = jk / dims[1];
  return {origin[0] + i * spacing[0], origin[1] + j * spacing[1], origin[2] + k * spacing[2]};
}

Eigen::MatrixXd Grid::points(int dim) const {
  if (dim < 1 || dim > 3) throw std::invalid_argument("Grid::points: dim must be 1, 2 or 3");
  for (int d = dim; d < 3; ++d)
    if (dims[d] > 1)
      throw std::invalid_argument("Grid::points: axis " + std::to_string(d) + " has " +
                                  std::to_string(dims[d]) + " points but dim is " +
                                  std::to_string(dim));
  const Eigen::Index n = point_count();
  Eigen::MatrixXd p(n, dim);
  for (Eigen::Index r = 0; r < n; ++r) p.row(r) = point(r).head(dim).transpose();
  return p;
}

Grid make_grid(const std::vector<double>& lower, const std::vector<double>& upper,
               const std::vector<int>& counts) {
  const std::size_t n = counts.size();
  if (n < 1 || n > 3 || lower.size() != n || upper.size() != n)
    throw std::invalid_argument("make_grid: lower, upper and counts need the same size, 1 to 3");
  Grid g;
  for (std::size_t d = 0; d < n; ++d) {
    if (counts[d] < 1) throw std::invalid_argument("make_grid: a count is below 1");
    g.dims[d] = counts[d];
    g.origin[d] = lower[d];
    g.spacing[d] = counts[d] > 1 ? (upper[d] - lower[d]) / (counts[d] - 1) : 1.0;
  }
  return g;
}

}  // namespace nfield::io
