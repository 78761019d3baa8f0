// SPDX-License-Identifier: MIT
#include "solvers/output/block_output.h"

#include <vector>

#include "fields/acorn.h"
#include "io/atomic_write.h"
#include "io/text.h"
#include "io/vtk_polydata.h"

namespace nfield::solvers {

io::PolyData block_poly_data(const fields::BlockTree& tree, const std::vector<double>& lower,
                             const std::vector<double>& upper) {
  const int d = tree.dim(), corners = 1 << d;
  const auto count = static_cast<Eigen::Index>(tree.blocks().size());
  io::PolyData data;
  data.points.setZero(count * corners, 3);
  Eigen::MatrixXd level(count * corners, 1), error(count * corners, 1), frozen(count * corners, 1);
  // The corners of the unit square/cube in the order v = Σ_j v_j 2^j; faces as triangles and
  // edges as segments over those numbers.
  static const std::vector<std::array<int, 3>> square{{0, 1, 3}, {0, 3, 2}};
  static const std::vector<std::array<int, 3>> cube{{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},
                                                    {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                                    {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  std::vector<std::array<int, 2>> edges;
  for (int v = 0; v < corners; ++v)
    for (int j = 0; j < d; ++j)
      if (!((v >> j) & 1)) edges.push_back({v, v | (1 << j)});
  const auto& faces = d == 2 ? square : d == 3 ? cube : std::vector<std::array<int, 3>>{};
  data.lines.resize(count * static_cast<Eigen::Index>(edges.size()), 2);
  data.triangles.resize(count * static_cast<Eigen::Index>(faces.size()), 3);
  for (Eigen::Index b = 0; b < count; ++b) {
    const fields::Block& block = tree.blocks()[static_cast<size_t>(b)];
    const double h = tree.size(static_cast<int>(b));
    const auto first = static_cast<int>(b * corners);
    for (int v = 0; v < corners; ++v) {
      const Eigen::Index p = first + v;
      for (int j = 0; j < d; ++j) {
        const auto sj = static_cast<size_t>(j);
        const double u = tree.lower(static_cast<int>(b), j) + (((v >> j) & 1) ? h : 0.0);
        const double lo = lower.size() > sj ? lower[sj] : 0.0, hi = upper.size() > sj ? upper[sj] : 1.0;
        data.points(p, j) = lo + (hi - lo) * u;
      }
      level(p) = block.level;
      error(p) = block.error;
      frozen(p) = block.frozen ? 1 : 0;
    }
    for (size_t e = 0; e < edges.size(); ++e)
      data.lines.row(b * static_cast<Eigen::Index>(edges.size()) + static_cast<Eigen::Index>(e)) << first + edges[e][0], first + edges[e][1];
    for (size_t f = 0; f < faces.size(); ++f)
      data.triangles.row(b * static_cast<Eigen::Index>(faces.size()) + static_cast<Eigen::Index>(f))
          << first + faces[f][0], first + faces[f][1], first + faces[f][2];
  }
  data.arrays["level"] = level;
  data.arrays["error"] = error;
  data.arrays["frozen"] = frozen;
  return data;
}

void write_block_outputs(const fields::FieldOptions& field, const std::filesystem::path& dir) {
  if (io::to_lower(field.type) != "acorn") return;
  const auto& tree = fields::acorn_options(field).tree;
  if (!tree) return;
  const io::PolyData data = block_poly_data(*tree, field.encoding.lower, field.encoding.upper);
  io::write_atomically(dir / "blocks.vtp", [&](const std::filesystem::path& p) { io::write_vtp(p, data); });
}

}  // namespace nfield::solvers
