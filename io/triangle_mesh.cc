// SPDX-License-Identifier: MIT
#include "io/triangle_mesh.h"

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>
#include <Eigen/Geometry>

#include "io/text_numbers.h"
#include "io/vtk_convert.h"
#include "io/vtk_errors.h"
#include "io/vtk_polydata_read.h"

namespace nfield::io {
namespace fs = std::filesystem;

namespace {
constexpr const char* kSupported = ".ply, .obj, .off, .vtp, .stl";

// Object File Format: [C][N]OFF, counts "V F E", V vertex lines "x y z [nx ny nz] [colour]",
// F face lines "n i1 .. in [colour]" (split into a fan of triangles).
TriangleMesh read_off(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("read_triangle_mesh: '" + path.string() + "': cannot open");
  std::string line;
  int line_no = 0;
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("read_triangle_mesh: '" + path.string() + "', line " +
                              std::to_string(line_no) + ": " + why);
  };
  std::vector<double> v;
  // The numbers of the next line that has any; false at the end of the file.
  const auto next = [&]() {
    while (std::getline(in, line)) {
      ++line_no;
      if (!parse_numbers(line, v)) throw fail("expected numbers: '" + line + "'");
      if (!v.empty()) return true;
    }
    return false;
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") != std::string::npos && line[0] != '#') break;
  }
  std::smatch m;
  static const std::regex header(R"(\s*(C?)(N?)OFF(\s+.*)?)");
  if (!std::regex_match(line, m, header)) throw fail("not an OFF header: '" + line + "'");
  const bool normals = m[2].length() > 0;
  if (!parse_numbers(m[3].str(), v)) throw fail("unsupported OFF header (binary OFF?)");
  if (v.empty() && !next()) throw fail("missing vertex and face counts");
  const auto count = [](double c) { return c >= 0 && c < 2e9 && c == std::floor(c); };
  if (v.size() < 2 || !count(v[0]) || !count(v[1])) throw fail("expected vertex and face counts");
  const auto nv = static_cast<Eigen::Index>(v[0]), nf = static_cast<Eigen::Index>(v[1]);
  TriangleMesh mesh;
  mesh.vertices.resize(nv, 3);
  if (normals) mesh.normals.resize(nv, 3);
  const std::size_t width = normals ? 6 : 3;
  for (Eigen::Index i = 0; i < nv; ++i) {
    if (!next()) throw fail("the file ends before vertex " + std::to_string(i));
    if (v.size() < width) throw fail("expected " + std::to_string(width) + " numbers");
    mesh.vertices.row(i) << v[0], v[1], v[2];
    if (normals) mesh.normals.row(i) << v[3], v[4], v[5];
  }
  std::vector<Eigen::Vector3i> triangles;
  for (Eigen::Index f = 0; f < nf; ++f) {
    if (!next()) throw fail("the file ends before face " + std::to_string(f));
    if (!(v[0] >= 3 && v[0] == std::floor(v[0]) && v[0] < static_cast<double>(v.size())))
      throw fail("expected a vertex count of at least 3 and that many indices");
    const auto n = static_cast<std::size_t>(v[0]);
    std::vector<int> ids(n);
    for (std::size_t j = 0; j < n; ++j) {
      const double id = v[j + 1];
      if (!(id >= 0 && id < static_cast<double>(nv) && id == std::floor(id))) {
        std::ostringstream text;
        text << "vertex index " << id << " is not one of 0.." << nv - 1;
        throw fail(text.str());
      }
      ids[j] = static_cast<int>(id);
    }
    for (std::size_t j = 1; j + 1 < n; ++j) triangles.emplace_back(ids[0], ids[j], ids[j + 1]);
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    mesh.triangles.row(static_cast<Eigen::Index>(t)) = triangles[t].transpose();
  return mesh;
}
}  // namespace

TriangleMesh read_triangle_mesh(const fs::path& path) {
  const std::string ext = lower_extension(path);
  TriangleMesh mesh;
  if (ext == ".off") {
    if (!fs::is_regular_file(path))
      throw std::runtime_error("read_triangle_mesh: '" + path.string() + "': no such file");
    mesh = read_off(path);
  } else {
    auto data = read_vtk_polydata(path, "read_triangle_mesh", kSupported);
    PolyData pd = from_vtk_polydata(data);
    mesh.vertices = std::move(pd.points);
    mesh.triangles = std::move(pd.triangles);
    if (vtkDataArray* n = data->GetPointData()->GetNormals(); n && n->GetNumberOfComponents() == 3)
      mesh.normals = from_vtk_array(n);
  }
  if (mesh.triangles.rows() == 0)
    throw std::runtime_error("read_triangle_mesh: '" + path.string() + "': no triangles");
  return mesh;
}

Eigen::MatrixXd vertex_normals(const TriangleMesh& mesh) {
  auto poly = to_vtk_polydata(PolyData{mesh.vertices, {}, mesh.triangles, {}}, Precision::kFloat64);
  vtkNew<vtkPolyDataNormals> filter;
  VtkErrorCatcher errors(filter);
  filter->SetInputData(poly);
  filter->SplittingOff();
  filter->ConsistencyOn();
  filter->AutoOrientNormalsOff();
  filter->ComputePointNormalsOn();
  filter->ComputeCellNormalsOff();
  filter->Update();
  vtkPolyData* out = filter->GetOutput();
  vtkDataArray* n = out->GetPointData()->GetNormals();
  if (errors.failed() || !n || n->GetNumberOfTuples() != mesh.vertices.rows())
    throw std::runtime_error("vertex_normals: vtkPolyDataNormals failed: " + errors.message());
  Eigen::MatrixXd normals = from_vtk_array(n);
  // Signed volume (times 6) of the consistently oriented triangles, seen from the centroid.
  const PolyData oriented = from_vtk_polydata(out);
  const Eigen::RowVector3d c = oriented.points.colwise().mean();
  double volume = 0;
  for (Eigen::Index t = 0; t < oriented.triangles.rows(); ++t) {
    Eigen::Vector3d p[3];
    for (int j = 0; j < 3; ++j)
      p[j] = (oriented.points.row(oriented.triangles(t, j)) - c).transpose();
    volume += p[0].dot(p[1].cross(p[2]));
  }
  const double sign = volume < 0 ? -1 : 1;
  for (Eigen::Index i = 0; i < normals.rows(); ++i)  // float in VTK: renormalise in double
    if (const double len = normals.row(i).norm(); len > 0) normals.row(i) *= sign / len;
  return normals;
}

}  // namespace nfield::io
