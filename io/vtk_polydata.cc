// SPDX-License-Identifier: MIT
#include "io/vtk_polydata.h"

#include <stdexcept>

#include <vtkNew.h>
#include <vtkPLYWriter.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataWriter.h>

#include "io/atomic_write.h"
#include "io/vtk_convert.h"
#include "io/vtk_errors.h"
#include "io/vtk_polydata_read.h"

namespace nfield::io {
namespace fs = std::filesystem;

namespace {
vtkSmartPointer<vtkPolyData> convert(const char* caller, const fs::path& path, const PolyData& data,
                                     Precision precision, bool vertices) {
  try {
    return to_vtk_polydata(data, precision, vertices);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(caller) + ": '" + path.string() + "': " + e.what());
  }
}

PolyData mesh_data(const TriangleMesh& mesh, const PointArrays& arrays) {
  PolyData data{mesh.vertices, {}, mesh.triangles, arrays};
  if (mesh.normals.size()) data.arrays["Normals"] = mesh.normals;
  return data;
}
}  // namespace

void write_vtp(const fs::path& path, const PolyData& data, Precision precision) {
  auto poly = convert("write_vtp", path, data, precision, true);
  write_atomically(path, [&](const fs::path& tmp) {
    vtkNew<vtkXMLPolyDataWriter> writer;
    VtkErrorCatcher errors(writer);
    writer->SetInputData(poly);
    writer->SetFileName(tmp.c_str());
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetCompressorTypeToZLib();
    writer->SetHeaderTypeToUInt64();
    if (!writer->Write() || errors.failed())
      throw std::runtime_error("vtkXMLPolyDataWriter: " + errors.message());
  });
}

void write_vtp_points(const fs::path& path, const Eigen::MatrixXd& points,
                      const PointArrays& arrays, Precision precision) {
  write_vtp(path, PolyData{points, {}, {}, arrays}, precision);
}

void write_vtp_mesh(const fs::path& path, const TriangleMesh& mesh, const PointArrays& arrays,
                    Precision precision) {
  write_vtp(path, mesh_data(mesh, arrays), precision);
}

PolyData read_vtp(const fs::path& path) {
  if (lower_extension(path) != ".vtp")
    throw std::runtime_error("read_vtp: '" + path.string() + "': the name does not end in .vtp");
  return from_vtk_polydata(read_vtk_polydata(path, "read_vtp", ".vtp"));
}

void write_ply(const fs::path& path, const TriangleMesh& mesh) {
  auto poly = convert("write_ply", path, PolyData{mesh.vertices, {}, mesh.triangles, {}},
                      Precision::kFloat32, false);
  write_atomically(path, [&](const fs::path& tmp) {
    vtkNew<vtkPLYWriter> writer;
    VtkErrorCatcher errors(writer);
    writer->SetInputData(poly);
    writer->SetFileName(tmp.c_str());
    writer->SetFileTypeToBinary();
    writer->SetDataByteOrderToLittleEndian();
    if (!writer->Write() || errors.failed() || writer->GetErrorCode())
      throw std::runtime_error("vtkPLYWriter: " + errors.message());
  });
}

}  // namespace nfield::io
