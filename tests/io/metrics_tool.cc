// SPDX-License-Identifier: MIT
//
// The figures of io/image_metrics.h and io/mesh_distance.h for inputs that an independent
// implementation also reads (tests/io/metrics_reference.py: scikit-image and SciPy), in raw
// little-endian files so that both sides see the same numbers bit for bit:
//
//   metrics_tool png IN.png OUT.f32      the image as io::read_png gives it, float32 in pixel
//                                        order (row, column, channel); prints "W H C"
//   metrics_tool mesh IN OUT_PREFIX      the mesh as io::read_triangle_mesh gives it:
//                                        OUT_PREFIX.v.f64 (n × 3), OUT_PREFIX.t.i32 (m × 3);
//                                        prints "n m"
//   metrics_tool compare MANIFEST        per line of MANIFEST, either
//                                          image NAME W H C A.f32 B.f32
//                                        printing "image NAME psnr ssim", or
//                                          mesh NAME A_PREFIX B_PREFIX
//                                        printing "mesh NAME a_to_b b_to_a normal_consistency"
//                                        (Chamfer means of a's vertices to b and back)
// Figures are printed with 17 significant digits.
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/image_metrics.h"
#include "io/mesh_distance.h"
#include "io/png_image.h"
#include "io/triangle_mesh.h"

namespace {

namespace fs = std::filesystem;
using nfield::io::TriangleMesh;

template <class T>
std::vector<T> read_raw(const fs::path& path, std::size_t count) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  std::vector<T> data(count);
  in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(count * sizeof(T)));
  if (in.gcount() != static_cast<std::streamsize>(count * sizeof(T)) || in.peek() != EOF)
    throw std::runtime_error(path.string() + " does not hold " + std::to_string(count) + " values");
  return data;
}

template <class T>
void write_raw(const fs::path& path, const std::vector<T>& data) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(T)));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

Eigen::MatrixXf read_image(const fs::path& path, int width, int height, int channels) {
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  const std::vector<float> raw = read_raw<float>(path, pixels * channels);
  Eigen::MatrixXf image(pixels, channels);
  for (std::size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < channels; ++c) image(p, c) = raw[p * channels + c];
  return image;
}

TriangleMesh read_mesh(const std::string& prefix) {
  const auto count = [](const fs::path& path, std::size_t size) { return fs::file_size(path) / (3 * size); };
  const fs::path v = prefix + ".v.f64", t = prefix + ".t.i32";
  const std::size_t n = count(v, sizeof(double)), m = count(t, sizeof(std::int32_t));
  const std::vector<double> vertices = read_raw<double>(v, 3 * n);
  const std::vector<std::int32_t> triangles = read_raw<std::int32_t>(t, 3 * m);
  TriangleMesh mesh;
  mesh.vertices.resize(n, 3);
  mesh.triangles.resize(m, 3);
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) mesh.vertices(i, a) = vertices[3 * i + a];
  for (std::size_t i = 0; i < m; ++i)
    for (int a = 0; a < 3; ++a) mesh.triangles(i, a) = triangles[3 * i + a];
  return mesh;
}

int dump_png(const fs::path& in, const fs::path& out) {
  const nfield::io::Image image = nfield::io::read_png(in);
  std::vector<float> raw(image.pixels.size());
  for (Eigen::Index p = 0; p < image.pixels.rows(); ++p)
    for (int c = 0; c < image.channels; ++c) raw[p * image.channels + c] = image.pixels(p, c);
  write_raw(out, raw);
  std::printf("%d %d %d\n", image.width, image.height, image.channels);
  return 0;
}

int dump_mesh(const fs::path& in, const std::string& prefix) {
  const TriangleMesh mesh = nfield::io::read_triangle_mesh(in);
  std::vector<double> vertices(mesh.vertices.size());
  std::vector<std::int32_t> triangles(mesh.triangles.size());
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
    for (int a = 0; a < 3; ++a) vertices[3 * i + a] = mesh.vertices(i, a);
  for (Eigen::Index i = 0; i < mesh.triangles.rows(); ++i)
    for (int a = 0; a < 3; ++a) triangles[3 * i + a] = mesh.triangles(i, a);
  write_raw(prefix + ".v.f64", vertices);
  write_raw(prefix + ".t.i32", triangles);
  std::printf("%ld %ld\n", static_cast<long>(mesh.vertices.rows()), static_cast<long>(mesh.triangles.rows()));
  return 0;
}

int compare(const fs::path& manifest) {
  std::ifstream in(manifest);
  if (!in) throw std::runtime_error("cannot open " + manifest.string());
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string kind, name;
    if (!(words >> kind >> name)) continue;
    if (kind == "image") {
      int width, height, channels;
      std::string a, b;
      if (!(words >> width >> height >> channels >> a >> b)) throw std::runtime_error("bad line: " + line);
      const Eigen::MatrixXf x = read_image(a, width, height, channels), y = read_image(b, width, height, channels);
      std::printf("image %s %.17g %.17g\n", name.c_str(), nfield::io::psnr(x, y),
                  nfield::io::ssim(x, y, width, height));
    } else if (kind == "mesh") {
      std::string a, b;
      if (!(words >> a >> b)) throw std::runtime_error("bad line: " + line);
      const nfield::io::SurfaceComparison c = nfield::io::compare_surfaces(read_mesh(a), read_mesh(b));
      std::printf("mesh %s %.17g %.17g %.17g\n", name.c_str(), c.a_to_b.mean(), c.b_to_a.mean(),
                  c.normal_consistency);
    } else {
      throw std::runtime_error("unknown kind '" + kind + "' in: " + line);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() == 3 && args[0] == "png") return dump_png(args[1], args[2]);
    if (args.size() == 3 && args[0] == "mesh") return dump_mesh(args[1], args[2]);
    if (args.size() == 2 && args[0] == "compare") return compare(args[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "metrics_tool: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "usage: metrics_tool png IN.png OUT.f32 | mesh IN OUT_PREFIX | compare MANIFEST\n");
  return 2;
}
