// SPDX-License-Identifier: MIT
#include "io/vtk_unstructured.h"

#include <array>
#include <stdexcept>
#include <vector>

#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "io/atomic_write.h"
#include "io/vtk_convert.h"
#include "io/vtk_errors.h"

namespace nfield::io {
namespace fs = std::filesystem;

void write_vtu(const fs::path& path, const TriangleGrid& data, Precision precision) {
  const Eigen::Index n = data.points.rows();
  if (data.triangles.size() && (data.triangles.minCoeff() < 0 || data.triangles.maxCoeff() >= n))
    throw std::invalid_argument("write_vtu: '" + path.string() + "': a triangle refers to a point that does not exist");
  vtkNew<vtkUnstructuredGrid> grid;
  try {
    grid->SetPoints(to_vtk_points(data.points, precision));
    grid->SetCells(VTK_TRIANGLE, to_vtk_cells<3>(data.triangles));
    add_point_arrays(grid->GetPointData(), data.arrays, n, precision);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("write_vtu: '" + path.string() + "': " + e.what());
  }
  write_atomically(path, [&](const fs::path& tmp) {
    vtkNew<vtkXMLUnstructuredGridWriter> writer;
    VtkErrorCatcher errors(writer);
    writer->SetInputData(grid);
    writer->SetFileName(tmp.c_str());
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetCompressorTypeToZLib();
    writer->SetHeaderTypeToUInt64();
    if (!writer->Write() || errors.failed())
      throw std::runtime_error("vtkXMLUnstructuredGridWriter: " + errors.message());
  });
}

TriangleGrid read_vtu(const fs::path& path) {
  if (!fs::exists(path)) throw std::runtime_error("read_vtu: '" + path.string() + "' does not exist");
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  VtkErrorCatcher errors(reader);
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (errors.failed() || !grid || !grid->GetPoints())
    throw std::runtime_error("read_vtu: '" + path.string() + "' is not a VTK unstructured grid: " + errors.message());
  TriangleGrid out;
  out.points = from_vtk_points(grid->GetPoints());
  std::vector<std::array<int, 3>> triangles;
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TRIANGLE) continue;
    grid->GetCellPoints(c, ids);
    triangles.push_back({static_cast<int>(ids->GetId(0)), static_cast<int>(ids->GetId(1)), static_cast<int>(ids->GetId(2))});
  }
  out.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) out.triangles(static_cast<Eigen::Index>(t), k) = triangles[t][static_cast<size_t>(k)];
  out.arrays = get_point_arrays(grid->GetPointData());
  return out;
}

}  // namespace nfield::io
