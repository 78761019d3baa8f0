// SPDX-License-Identifier: MIT
//
// Cost of the SDF problem's surface metrics (io/mesh_distance.h: Chamfer distances both ways
// and normal consistency) for the zero level set of a 256³ grid against the Stanford bunny
// (75,408 triangles), on one thread and on all, as `nfield run` computes them after an SDF
// run. The target: at most 5 s for a 256³ grid's surface.
//
// The level set is that of u = d(x) − ε, d the distance to the bunny and ε half a grid cell:
// the two sheets of a thin shell around the bunny, so about twice the vertices of a trained
// field's surface at the same grid (a conservative case). d is computed in a narrow band
// only: on a 64³ grid first, then on the fine points whose coarse cell can reach the band.
//
// Then the inputs of sign_accuracy on the same grid (io/inside_mesh.h, near_mesh).
//
// Run: build/bench/chamfer_bench [grid (256)] [mesh (data/meshes/bunny00.ply)]
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "io/grid.h"
#include "io/inside_mesh.h"
#include "io/isosurface.h"
#include "io/mesh_distance.h"
#include "io/triangle_mesh.h"

using namespace nfield;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 256;
  const std::string mesh_path = argc > 2 ? argv[2] : NFIELD_SOURCE_DIR "/data/meshes/bunny00.ply";
  if (n < 8 || n > 1024) {
    std::fprintf(stderr, "chamfer_bench: grid %d: expected 8 to 1024\n", n);
    return 2;
  }
  const io::TriangleMesh mesh = io::read_triangle_mesh(mesh_path);
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff(), hi = mesh.vertices.colwise().maxCoeff();
  const double pad = 0.1 * (hi - lo).maxCoeff();
  const std::vector<double> lower{lo(0) - pad, lo(1) - pad, lo(2) - pad}, upper{hi(0) + pad, hi(1) + pad, hi(2) + pad};

  // 1. The shell's level set on the n³ grid, through a 64³ coarse pass.
  auto started = std::chrono::steady_clock::now();
  const io::Grid fine = io::make_grid(lower, upper, {n, n, n});
  const io::Grid coarse = io::make_grid(lower, upper, {64, 64, 64});
  const Eigen::VectorXd coarse_distance = io::mesh_distance(coarse.points(3), mesh);
  const double epsilon = 0.5 * fine.spacing[0];
  const double reach = Eigen::Vector3d(coarse.spacing[0], coarse.spacing[1], coarse.spacing[2]).norm();
  const Eigen::MatrixXd points = fine.points(3);
  std::vector<Eigen::Index> band;
  Eigen::VectorXd u(points.rows());
  for (Eigen::Index p = 0; p < points.rows(); ++p) {
    int c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(static_cast<int>(std::lround((points(p, a) - coarse.origin[a]) / coarse.spacing[a])), 0, 63);
    const double near = coarse_distance(c[0] + 64 * (c[1] + 64 * c[2]));
    if (near - reach > epsilon) {
      u(p) = near - reach - epsilon;  // a lower bound of d − ε: positive, as d − ε is
    } else {
      band.push_back(p);
    }
  }
  Eigen::MatrixXd band_points(static_cast<Eigen::Index>(band.size()), 3);
  for (std::size_t k = 0; k < band.size(); ++k) band_points.row(k) = points.row(band[k]);
  const Eigen::VectorXd band_distance = io::mesh_distance(band_points, mesh);
  for (std::size_t k = 0; k < band.size(); ++k) u(band[k]) = band_distance(k) - epsilon;
  const io::TriangleMesh surface = io::extract_isosurface(fine, u, 0.0, true);
  std::printf("level set of a %d^3 grid: %ld vertices, %ld triangles (set-up %.1f s, %zu band points)\n", n,
              static_cast<long>(surface.vertices.rows()), static_cast<long>(surface.triangles.rows()),
              seconds_since(started), band.size());
  std::printf("reference %s: %ld vertices, %ld triangles\n", mesh_path.c_str(),
              static_cast<long>(mesh.vertices.rows()), static_cast<long>(mesh.triangles.rows()));

  // 2. The metrics on one thread (the code before it ran threaded), then on all.
  const int threads = omp_get_max_threads();
  double times[2];
  io::SurfaceComparison results[2];
  for (int k = 0; k < 2; ++k) {
    omp_set_num_threads(k == 0 ? 1 : threads);
    started = std::chrono::steady_clock::now();
    results[k] = io::compare_surfaces(surface, mesh);
    times[k] = seconds_since(started);
    std::printf("%d thread%s: %.2f s (chamfer mean %.4e, max %.4e, normal consistency %.4f)\n",
                k == 0 ? 1 : threads, k == 0 ? "" : "s", times[k], results[k].chamfer_mean(),
                results[k].chamfer_max(), results[k].normal_consistency);
  }
  omp_set_num_threads(threads);

  // 3. The inputs of sign_accuracy on the same grid: inside/outside by crossing parity, and
  // which points lie within 5 % of the diagonal of the surface.
  started = std::chrono::steady_clock::now();
  const auto inside = io::inside_closed_mesh(fine, mesh);
  const double parity_s = seconds_since(started);
  started = std::chrono::steady_clock::now();
  const auto near = io::grid_near_mesh(fine, mesh, 0.05 * (hi - lo).norm());
  std::printf("sign inputs on %ld grid points: inside by parity %.2f s (%ld inside), band %.2f s (%ld near)\n",
              static_cast<long>(points.rows()), parity_s, static_cast<long>(inside.count()), seconds_since(started),
              static_cast<long>(near.count()));
  const bool same = results[0].a_to_b == results[1].a_to_b && results[0].b_to_a == results[1].b_to_a;
  std::printf("speed-up %.2fx over one thread; threaded results %s; target <= 5 s: %s\n", times[0] / times[1],
              same ? "identical" : "DIFFER", times[1] <= 5.0 ? "met" : "NOT met");
  return same ? 0 : 1;
}
