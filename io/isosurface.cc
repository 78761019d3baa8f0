// SPDX-License-Identifier: MIT
#include "io/isosurface.h"

#include <stdexcept>
#include <string>

#include <vtkDataArray.h>
#include <vtkFlyingEdges2D.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include "io/vtk_convert.h"
#include "io/vtk_errors.h"

namespace nfield::io {

namespace {
vtkSmartPointer<vtkImageData> image_of(const char* caller, const Grid& grid,
                                       const Eigen::VectorXd& values) {
  if (values.size() != grid.point_count())
    throw std::invalid_argument(std::string(caller) + ": " + std::to_string(values.size()) +
                                " values for a grid of " + std::to_string(grid.point_count()) +
                                " points");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(grid.dims.data());
  image->SetOrigin(grid.origin.data());
  image->SetSpacing(grid.spacing.data());
  image->GetPointData()->SetScalars(to_vtk_array("values", values, Precision::kFloat64));
  return image;
}

template <class Filter>
vtkPolyData* run(Filter* filter, vtkImageData* image, double iso, const char* caller) {
  VtkErrorCatcher errors(filter);
  filter->SetInputData(image);
  filter->SetValue(0, iso);
  filter->ComputeScalarsOff();
  filter->Update();
  if (errors.failed()) throw std::runtime_error(std::string(caller) + ": " + errors.message());
  return filter->GetOutput();
}
}  // namespace

TriangleMesh extract_isosurface(const Grid& grid, const Eigen::VectorXd& values, double iso,
                                bool normals) {
  if (grid.dims[0] < 2 || grid.dims[1] < 2 || grid.dims[2] < 2)
    throw std::invalid_argument("extract_isosurface: the grid needs 2 or more points per axis");
  auto image = image_of("extract_isosurface", grid, values);
  vtkNew<vtkFlyingEdges3D> filter;
  filter->SetComputeNormals(normals);
  filter->ComputeGradientsOff();
  vtkPolyData* out = run(filter.Get(), image, iso, "extract_isosurface");
  PolyData pd = from_vtk_polydata(out);
  TriangleMesh mesh{std::move(pd.points), std::move(pd.triangles), {}};
  // VTK winds triangles and points normals toward smaller values; turn both around.
  mesh.triangles.col(1).swap(mesh.triangles.col(2));
  if (vtkDataArray* n = out->GetPointData()->GetNormals(); normals && n)
    mesh.normals = -from_vtk_array(n);
  return mesh;
}

ContourLines extract_contour_lines(const Grid& grid, const Eigen::VectorXd& values, double iso) {
  if (grid.dims[0] < 2 || grid.dims[1] < 2 || grid.dims[2] != 1)
    throw std::invalid_argument(
        "extract_contour_lines: the grid needs 2 or more points along x and y, one along z");
  auto image = image_of("extract_contour_lines", grid, values);
  vtkNew<vtkFlyingEdges2D> filter;
  PolyData pd = from_vtk_polydata(run(filter.Get(), image, iso, "extract_contour_lines"));
  return {pd.points.leftCols(2), std::move(pd.lines)};
}

}  // namespace nfield::io
