// SPDX-License-Identifier: MIT
#include "io/vtk_convert.h"

#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

namespace nfield::io {

namespace {
template <class VtkArray>
vtkSmartPointer<vtkDataArray> make_array(const std::string& name, const Eigen::MatrixXd& m) {
  using T = typename VtkArray::ValueType;
  auto a = vtkSmartPointer<VtkArray>::New();
  a->SetName(name.c_str());
  a->SetNumberOfComponents(static_cast<int>(m.cols()));
  a->SetNumberOfTuples(m.rows());
  Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      a->GetPointer(0), m.rows(), m.cols()) = m.cast<T>();
  return a;
}

template <class T>
Eigen::MatrixXd read_typed(const T* p, Eigen::Index rows, Eigen::Index cols) {
  return Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
             p, rows, cols)
      .template cast<double>();
}
}  // namespace

vtkSmartPointer<vtkDataArray> to_vtk_array(const std::string& name, const Eigen::MatrixXd& m,
                                           Precision precision) {
  return precision == Precision::kFloat32 ? make_array<vtkFloatArray>(name, m)
                                          : make_array<vtkDoubleArray>(name, m);
}

Eigen::MatrixXd from_vtk_array(vtkDataArray* a) {
  const Eigen::Index rows = a->GetNumberOfTuples(), cols = a->GetNumberOfComponents();
  if (auto* d = vtkDoubleArray::FastDownCast(a)) return read_typed(d->GetPointer(0), rows, cols);
  if (auto* f = vtkFloatArray::FastDownCast(a)) return read_typed(f->GetPointer(0), rows, cols);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) m(r, c) = a->GetComponent(r, static_cast<int>(c));
  return m;
}

void add_point_arrays(vtkDataSetAttributes* data, const PointArrays& arrays, Eigen::Index rows,
                      Precision precision) {
  for (const auto& [name, m] : arrays) {
    if (m.rows() != rows || m.cols() < 1)
      throw std::invalid_argument("point array '" + name + "' is " + std::to_string(m.rows()) +
                                  "x" + std::to_string(m.cols()) + " but there are " +
                                  std::to_string(rows) + " points");
    auto a = to_vtk_array(name, m, precision);
    if (name == "Normals" && m.cols() == 3)
      data->SetNormals(a);
    else
      data->AddArray(a);
  }
}

PointArrays get_point_arrays(vtkDataSetAttributes* data) {
  PointArrays out;
  for (int i = 0; i < data->GetNumberOfArrays(); ++i)
    if (vtkDataArray* a = data->GetArray(i); a && a->GetName())
      out[a->GetName()] = from_vtk_array(a);
  return out;
}

vtkSmartPointer<vtkPoints> to_vtk_points(const Eigen::MatrixXd& points, Precision precision) {
  if (points.cols() != 2 && points.cols() != 3)
    throw std::invalid_argument("points need 2 or 3 columns, not " + std::to_string(points.cols()));
  Eigen::MatrixXd p3 = Eigen::MatrixXd::Zero(points.rows(), 3);
  p3.leftCols(points.cols()) = points;
  auto p = vtkSmartPointer<vtkPoints>::New();
  p->SetData(to_vtk_array("Points", p3, precision));
  return p;
}

Eigen::MatrixXd from_vtk_points(vtkPoints* points) {
  if (!points) return Eigen::MatrixXd(0, 3);
  return from_vtk_array(points->GetData());
}

template <int K>
vtkSmartPointer<vtkCellArray> to_vtk_cells(const Eigen::Matrix<int, Eigen::Dynamic, K>& cells) {
  const vtkIdType n = cells.rows(), k = cells.cols();
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(n + 1);
  connectivity->SetNumberOfValues(n * k);
  for (vtkIdType c = 0; c <= n; ++c) offsets->SetValue(c, c * k);
  for (vtkIdType c = 0; c < n; ++c)
    for (vtkIdType j = 0; j < k; ++j) connectivity->SetValue(c * k + j, cells(c, j));
  auto out = vtkSmartPointer<vtkCellArray>::New();
  out->SetData(offsets, connectivity);
  return out;
}

template vtkSmartPointer<vtkCellArray> to_vtk_cells<1>(
    const Eigen::Matrix<int, Eigen::Dynamic, 1>&);
template vtkSmartPointer<vtkCellArray> to_vtk_cells<2>(
    const Eigen::Matrix<int, Eigen::Dynamic, 2>&);
template vtkSmartPointer<vtkCellArray> to_vtk_cells<3>(
    const Eigen::Matrix<int, Eigen::Dynamic, 3>&);

namespace {
template <int K>
void check_indices(const Eigen::Matrix<int, Eigen::Dynamic, K>& cells, Eigen::Index n,
                   const char* what) {
  if (cells.size() && (cells.minCoeff() < 0 || cells.maxCoeff() >= n))
    throw std::invalid_argument(std::string(what) + " refer to points outside 0.." +
                                std::to_string(n - 1));
}

template <int K>
Eigen::Matrix<int, Eigen::Dynamic, K> cells_of_size(vtkCellArray* cells) {
  Eigen::Matrix<int, Eigen::Dynamic, K> out(cells ? cells->GetNumberOfCells() : 0, K);
  Eigen::Index rows = 0;
  if (cells) {
    vtkIdType size;
    const vtkIdType* ids;
    for (cells->InitTraversal(); cells->GetNextCell(size, ids);)
      if (size == K) {
        for (int j = 0; j < K; ++j) out(rows, j) = static_cast<int>(ids[j]);
        ++rows;
      }
  }
  return out.topRows(rows);
}
}  // namespace

vtkSmartPointer<vtkPolyData> to_vtk_polydata(const PolyData& data, Precision precision,
                                             bool vertices_if_no_cells) {
  const Eigen::Index n = data.points.rows();
  check_indices(data.lines, n, "lines");
  check_indices(data.triangles, n, "triangles");
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->SetPoints(to_vtk_points(data.points, precision));
  add_point_arrays(out->GetPointData(), data.arrays, n, precision);
  if (data.lines.rows()) out->SetLines(to_vtk_cells<2>(data.lines));
  if (data.triangles.rows()) out->SetPolys(to_vtk_cells<3>(data.triangles));
  if (vertices_if_no_cells && !data.lines.rows() && !data.triangles.rows())
    out->SetVerts(to_vtk_cells<1>(Eigen::VectorXi::LinSpaced(n, 0, static_cast<int>(n) - 1)));
  return out;
}

PolyData from_vtk_polydata(vtkPolyData* data) {
  PolyData out;
  out.points = from_vtk_points(data->GetPoints());
  out.lines = cells_of_size<2>(data->GetLines());
  out.triangles = cells_of_size<3>(data->GetPolys());
  out.arrays = get_point_arrays(data->GetPointData());
  return out;
}

}  // namespace nfield::io
