// SPDX-License-Identifier: MIT
#include "io/mesh_distance.h"

#include <cmath>
#include <stdexcept>

#include <vtkGenericCell.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkStaticCellLocator.h>

#include "io/vtk_convert.h"

namespace nfield::io {

Eigen::VectorXd mesh_distance(const Eigen::MatrixXd& points, const TriangleMesh& mesh) {
  if (mesh.triangles.rows() == 0)
    throw std::invalid_argument("mesh_distance: the mesh has no triangles");
  if (points.cols() != 3) throw std::invalid_argument("mesh_distance: points need 3 columns");
  auto poly = to_vtk_polydata(PolyData{mesh.vertices, {}, mesh.triangles, {}}, Precision::kFloat64);
  vtkNew<vtkStaticCellLocator> locator;
  locator->SetDataSet(poly);
  locator->BuildLocator();
  vtkNew<vtkGenericCell> cell;
  Eigen::VectorXd out(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    double x[3] = {points(i, 0), points(i, 1), points(i, 2)}, closest[3], dist2;
    vtkIdType cell_id;
    int sub_id;
    locator->FindClosestPoint(x, closest, cell, cell_id, sub_id, dist2);
    out(i) = std::sqrt(dist2);
  }
  return out;
}

ChamferDistance chamfer_distance(const TriangleMesh& a, const TriangleMesh& b) {
  return {mesh_distance(a.vertices, b).mean(), mesh_distance(b.vertices, a).mean()};
}

}  // namespace nfield::io
