// SPDX-License-Identifier: MIT
#include "io/mesh_distance.h"

#include <algorithm>
#include <array>
#include <vector>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <vtkGenericCell.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkStaticCellLocator.h>
#include <vtkStaticPointLocator.h>

#include "io/vtk_convert.h"

namespace nfield::io {
namespace {

Eigen::MatrixXd triangle_normals(const TriangleMesh& mesh, Eigen::VectorXd* areas);

Eigen::MatrixXd triangle_normals(const TriangleMesh& mesh, Eigen::VectorXd* areas) {
  Eigen::MatrixXd normals(mesh.triangles.rows(), 3);
  if (areas) areas->resize(mesh.triangles.rows());
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const Eigen::Vector3d p0 = mesh.vertices.row(mesh.triangles(t, 0)).transpose();
    const Eigen::Vector3d e1 = mesh.vertices.row(mesh.triangles(t, 1)).transpose() - p0;
    const Eigen::Vector3d e2 = mesh.vertices.row(mesh.triangles(t, 2)).transpose() - p0;
    const Eigen::Vector3d cross = e1.cross(e2);
    const double norm = cross.norm();
    normals.row(t) = norm > 0 ? Eigen::RowVector3d(cross.transpose() / norm) : Eigen::RowVector3d::Zero();
    if (areas) (*areas)(t) = 0.5 * norm;
  }
  return normals;
}

// The vertices that triangles use, with their area-weighted normals.
void used_vertices(const TriangleMesh& mesh, Eigen::MatrixXd& points, Eigen::MatrixXd& normals) {
  Eigen::VectorXd areas;
  const Eigen::MatrixXd face = triangle_normals(mesh, &areas);
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(mesh.vertices.rows(), 3);
  Eigen::Array<bool, Eigen::Dynamic, 1> used = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(mesh.vertices.rows(), false);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      sum.row(mesh.triangles(t, k)) += areas(t) * face.row(t);
      used(mesh.triangles(t, k)) = true;
    }
  points.resize(used.count(), 3);
  normals.resize(used.count(), 3);
  Eigen::Index row = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    if (!used(v)) continue;
    points.row(row) = mesh.vertices.row(v);
    const double norm = sum.row(v).norm();
    normals.row(row++) = norm > 0 ? Eigen::RowVector3d(sum.row(v) / norm) : Eigen::RowVector3d::Zero();
  }
}

// Mean of |n_i · m_{t(i)}| over the points.
double mean_alignment(const Eigen::MatrixXd& normals, const Eigen::MatrixXd& face_normals,
                      const Eigen::VectorXi& triangle) {
  double sum = 0;
  for (Eigen::Index i = 0; i < normals.rows(); ++i)
    sum += std::abs(normals.row(i).dot(face_normals.row(triangle(i))));
  return normals.rows() > 0 ? sum / static_cast<double>(normals.rows()) : 0.0;
}

// The mesh as VTK polydata with its cell locator, built once before the threads query it.
struct Located {
  vtkSmartPointer<vtkPolyData> poly;
  vtkNew<vtkStaticCellLocator> locator;
  explicit Located(const TriangleMesh& mesh)
      : poly(to_vtk_polydata(PolyData{mesh.vertices, {}, mesh.triangles, {}}, Precision::kFloat64)) {
    locator->SetDataSet(poly);
    locator->BuildLocator();
  }
};

}  // namespace

ClosestTriangles closest_triangles(const Eigen::MatrixXd& points, const TriangleMesh& mesh) {
  if (mesh.triangles.rows() == 0)
    throw std::invalid_argument("mesh_distance: the mesh has no triangles");
  if (points.cols() != 3) throw std::invalid_argument("mesh_distance: points need 3 columns");
  const Located located(mesh);
  vtkStaticCellLocator* locator = located.locator;
  ClosestTriangles out{Eigen::VectorXd(points.rows()), Eigen::VectorXi(points.rows())};
#pragma omp parallel
  {
    vtkNew<vtkGenericCell> cell;  // per thread: the locator's query is thread-safe with it
#pragma omp for schedule(dynamic, 1024)
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
      double x[3] = {points(i, 0), points(i, 1), points(i, 2)}, closest[3], dist2;
      vtkIdType cell_id;
      int sub_id;
      locator->FindClosestPoint(x, closest, cell, cell_id, sub_id, dist2);
      out.distance(i) = std::sqrt(dist2);
      out.triangle(i) = static_cast<int>(cell_id);
    }
  }
  return out;
}

Eigen::MatrixXd triangle_normals(const TriangleMesh& mesh) { return triangle_normals(mesh, nullptr); }

Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> nearest_cloud_points(const Eigen::MatrixXd& points,
                                                                     const Eigen::MatrixXd& cloud) {
  if (cloud.rows() == 0) throw std::invalid_argument("point_cloud_distance: the cloud is empty");
  if (points.cols() != 3 || cloud.cols() != 3)
    throw std::invalid_argument("point_cloud_distance: points need 3 columns");
  auto poly = to_vtk_polydata(PolyData{cloud, {}, {}, {}}, Precision::kFloat64);
  vtkNew<vtkStaticPointLocator> locator;
  locator->SetDataSet(poly);
  locator->BuildLocator();
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> out(points.rows());
#pragma omp parallel for schedule(dynamic, 1024)
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const double x[3] = {points(i, 0), points(i, 1), points(i, 2)};
    out(i) = locator->FindClosestPoint(x);
  }
  return out;
}

Eigen::VectorXd point_cloud_distance(const Eigen::MatrixXd& points, const Eigen::MatrixXd& cloud) {
  const auto nearest = nearest_cloud_points(points, cloud);
  Eigen::VectorXd out(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) out(i) = (points.row(i) - cloud.row(nearest(i))).norm();
  return out;
}

Eigen::Array<bool, Eigen::Dynamic, 1> near_mesh(const Eigen::MatrixXd& points, const TriangleMesh& mesh,
                                                double radius) {
  if (mesh.triangles.rows() == 0) throw std::invalid_argument("near_mesh: the mesh has no triangles");
  if (points.cols() != 3) throw std::invalid_argument("near_mesh: points need 3 columns");
  const Located located(mesh);
  vtkStaticCellLocator* locator = located.locator;
  Eigen::Array<bool, Eigen::Dynamic, 1> out(points.rows());
#pragma omp parallel
  {
    vtkNew<vtkGenericCell> cell;
#pragma omp for schedule(dynamic, 1024)
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
      double x[3] = {points(i, 0), points(i, 1), points(i, 2)}, closest[3], dist2;
      vtkIdType cell_id;
      int sub_id;
      out(i) = locator->FindClosestPointWithinRadius(x, radius, closest, cell, cell_id, sub_id, dist2) != 0;
    }
  }
  return out;
}

Eigen::Array<bool, Eigen::Dynamic, 1> grid_near_mesh(const Grid& grid, const TriangleMesh& mesh, double radius) {
  if (mesh.triangles.rows() == 0) throw std::invalid_argument("grid_near_mesh: the mesh has no triangles");
  const Located located(mesh);
  vtkStaticCellLocator* locator = located.locator;
  struct Block {
    std::array<int, 3> first, count;  // grid indices [first, first + count) per axis
  };
  Eigen::Array<bool, Eigen::Dynamic, 1> out =
      Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(grid.point_count(), false);
  const auto fill = [&](const Block& b, bool value) {
    for (int k = b.first[2]; k < b.first[2] + b.count[2]; ++k)
      for (int j = b.first[1]; j < b.first[1] + b.count[1]; ++j)
        for (int i = b.first[0]; i < b.first[0] + b.count[0]; ++i)
          out(i + static_cast<Eigen::Index>(grid.dims[0]) * (j + static_cast<Eigen::Index>(grid.dims[1]) * k)) = value;
  };
  // Blocks of 16³ points to start with.
  std::vector<Block> blocks;
  for (int k = 0; k < grid.dims[2]; k += 16)
    for (int j = 0; j < grid.dims[1]; j += 16)
      for (int i = 0; i < grid.dims[0]; i += 16)
        blocks.push_back({{i, j, k},
                          {std::min(16, grid.dims[0] - i), std::min(16, grid.dims[1] - j), std::min(16, grid.dims[2] - k)}});
  while (!blocks.empty()) {
    std::vector<std::vector<Block>> split(blocks.size());
#pragma omp parallel
    {
      vtkNew<vtkGenericCell> cell;
#pragma omp for schedule(dynamic, 16)
      for (long b = 0; b < static_cast<long>(blocks.size()); ++b) {
        const Block& block = blocks[b];
        double centre[3], half_diagonal2 = 0;
        for (int a = 0; a < 3; ++a) {
          const double extent = (block.count[a] - 1) * grid.spacing[a];
          centre[a] = grid.origin[a] + block.first[a] * grid.spacing[a] + 0.5 * extent;
          half_diagonal2 += 0.25 * extent * extent;
        }
        const double reach = std::sqrt(half_diagonal2);
        double closest[3], dist2;
        vtkIdType cell_id;
        int sub_id;
        // Nothing within radius + reach: the whole block is far.
        if (!locator->FindClosestPointWithinRadius(centre, radius + reach, closest, cell, cell_id, sub_id, dist2))
          continue;
        const double d = std::sqrt(dist2);
        if (reach == 0) {
          if (d < radius) fill(block, true);
        } else if (d + reach < radius) {
          fill(block, true);
        } else if (d - reach <= radius) {
          // Split each axis of more than one point in two.
          const std::array<int, 3> half{block.count[0] / 2, block.count[1] / 2, block.count[2] / 2};
          for (int c = 0; c < 8; ++c) {
            Block child = block;
            bool empty = false;
            for (int a = 0; a < 3; ++a) {
              const bool upper = (c >> a) & 1;
              if (block.count[a] == 1) {
                empty = empty || upper;
                continue;
              }
              child.first[a] = block.first[a] + (upper ? half[a] : 0);
              child.count[a] = upper ? block.count[a] - half[a] : half[a];
            }
            if (!empty) split[b].push_back(child);
          }
        }
      }
    }
    blocks.clear();
    for (const auto& children : split) blocks.insert(blocks.end(), children.begin(), children.end());
  }
  return out;
}

Eigen::VectorXd mesh_distance(const Eigen::MatrixXd& points, const TriangleMesh& mesh) {
  return closest_triangles(points, mesh).distance;
}

SurfaceComparison compare_surfaces(const TriangleMesh& a, const TriangleMesh& b) {
  if (a.triangles.rows() == 0 || b.triangles.rows() == 0)
    throw std::invalid_argument("compare_surfaces: a surface has no triangles");
  Eigen::MatrixXd a_points, a_normals, b_points, b_normals;
  used_vertices(a, a_points, a_normals);
  used_vertices(b, b_points, b_normals);
  const ClosestTriangles ab = closest_triangles(a_points, b), ba = closest_triangles(b_points, a);
  SurfaceComparison out;
  out.a_to_b = ab.distance;
  out.b_to_a = ba.distance;
  out.normal_consistency = 0.5 * (mean_alignment(a_normals, triangle_normals(b), ab.triangle) +
                                  mean_alignment(b_normals, triangle_normals(a), ba.triangle));
  return out;
}

ChamferDistance chamfer_distance(const TriangleMesh& a, const TriangleMesh& b) {
  const SurfaceComparison c = compare_surfaces(a, b);
  return {c.a_to_b.mean(), c.b_to_a.mean()};
}

}  // namespace nfield::io
