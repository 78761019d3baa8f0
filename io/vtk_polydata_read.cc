// SPDX-License-Identifier: MIT
#include "io/vtk_polydata_read.h"

#include <functional>
#include <stdexcept>

#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataReader.h>

#include "io/text.h"
#include "io/vtk_errors.h"

namespace nfield::io {
namespace fs = std::filesystem;

std::string lower_extension(const fs::path& path) {
  return to_lower(path.extension().string());
}

namespace {
// Runs `reader` on `path`; its output, or an error with VTK's messages.
template <class Reader>
vtkSmartPointer<vtkPolyData> run(Reader* reader, const fs::path& path,
                                 const std::function<std::runtime_error(std::string)>& fail) {
  VtkErrorCatcher errors(reader);
  reader->SetFileName(path.c_str());
  reader->Update();
  if (errors.failed()) throw fail(errors.message());
  vtkSmartPointer<vtkPolyData> out = reader->GetOutput();
  if (!out) throw fail("the reader produced no data");
  return out;
}
}  // namespace

vtkSmartPointer<vtkPolyData> read_vtk_polydata(const fs::path& path, const std::string& caller,
                                               const std::string& supported) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error(caller + ": '" + path.string() + "': " + why);
  };
  const std::string ext = lower_extension(path);
  // STL only for callers that list it (surfaces; a point cloud has no use for its triangles).
  const bool stl = ext == ".stl" && supported.find(".stl") != std::string::npos;
  if (ext != ".vtp" && ext != ".ply" && ext != ".obj" && !stl)
    throw fail("unknown extension '" + ext + "' (supported: " + supported + ")");
  if (!fs::is_regular_file(path)) throw fail("no such file");
  vtkSmartPointer<vtkPolyData> data;
  if (ext == ".vtp") {
    vtkNew<vtkXMLPolyDataReader> reader;
    if (!reader->CanReadFile(path.c_str())) throw fail("not a VTK XML polydata (.vtp) file");
    data = run(reader.Get(), path, fail);
  } else if (ext == ".ply") {
    if (!vtkPLYReader::CanReadFile(path.c_str())) throw fail("not a PLY file");
    vtkNew<vtkPLYReader> reader;
    data = run(reader.Get(), path, fail);
  } else if (stl) {
    // Merging (the default) joins the copies of a vertex that STL stores per triangle, so
    // that a closed surface reads back closed.
    vtkNew<vtkSTLReader> reader;
    reader->MergingOn();
    data = run(reader.Get(), path, fail);
  } else {
    vtkNew<vtkOBJReader> reader;
    data = run(reader.Get(), path, fail);
  }
  vtkNew<vtkTriangleFilter> triangles;
  VtkErrorCatcher errors(triangles);
  triangles->SetInputData(data);
  triangles->PassVertsOn();
  triangles->PassLinesOn();
  triangles->Update();
  if (errors.failed()) throw fail(errors.message());
  return triangles->GetOutput();
}

}  // namespace nfield::io
