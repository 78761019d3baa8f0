// SPDX-License-Identifier: MIT
#include "io/point_cloud.h"

#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include "io/text_numbers.h"
#include "io/triangle_mesh.h"
#include "io/vtk_convert.h"
#include "io/vtk_polydata_read.h"

namespace nfield::io {
namespace fs = std::filesystem;

namespace {
constexpr const char* kSupported = ".xyz, .pwn, .ply, .obj, .off, .vtp";

std::runtime_error error(const fs::path& path, const std::string& why) {
  return std::runtime_error("read_oriented_points: '" + path.string() + "': " + why);
}

OrientedPoints read_xyz(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw error(path, "cannot open");
  std::vector<double> all, v;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (!parse_numbers(line, v) || (!v.empty() && v.size() != 6))
      throw std::runtime_error("read_oriented_points: '" + path.string() + "', line " +
                               std::to_string(line_no) + ": expected 6 numbers " +
                               "(x y z nx ny nz), got '" + line + "'");
    all.insert(all.end(), v.begin(), v.end());
  }
  const Eigen::Index n = static_cast<Eigen::Index>(all.size() / 6);
  Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>> m(all.data(), n, 6);
  return {m.leftCols(3), m.rightCols(3)};
}

OrientedPoints from_mesh(TriangleMesh mesh) {
  if (mesh.normals.rows() != mesh.vertices.rows()) mesh.normals = vertex_normals(mesh);
  return {std::move(mesh.vertices), std::move(mesh.normals)};
}
}  // namespace

OrientedPoints read_oriented_points(const fs::path& path) {
  const std::string ext = lower_extension(path);
  OrientedPoints out;
  if (ext == ".xyz" || ext == ".pwn" || ext == ".off") {
    if (!fs::is_regular_file(path)) throw error(path, "no such file");
    if (ext == ".off")
      out = from_mesh(read_triangle_mesh(path));
    else
      out = read_xyz(path);
  } else {
    auto data = read_vtk_polydata(path, "read_oriented_points", kSupported);
    vtkDataArray* normals = data->GetPointData()->GetNormals();
    if (normals && normals->GetNumberOfComponents() == 3) {
      out = {from_vtk_points(data->GetPoints()), from_vtk_array(normals)};
    } else {
      PolyData pd = from_vtk_polydata(data);
      if (pd.triangles.rows() == 0) throw error(path, "no normals and no faces to compute them");
      out = from_mesh(TriangleMesh{std::move(pd.points), std::move(pd.triangles), {}});
    }
  }
  if (out.points.rows() == 0) throw error(path, "no points");
  for (Eigen::Index i = 0; i < out.normals.rows(); ++i)
    if (const double len = out.normals.row(i).norm(); len > 0) out.normals.row(i) /= len;
  return out;
}

}  // namespace nfield::io
