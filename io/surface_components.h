// SPDX-License-Identifier: MIT
//
// The connected pieces of a triangle surface: triangles that share a vertex belong to one
// piece (union-find over the mesh's vertex indices, so a surface whose
// triangles do not share vertices counts every triangle as a piece). A level set that should
// be one closed surface is checked with it: stray pieces far from the object show up as
// more components and a largest-piece share of the area below 1.
#pragma once
#include <Eigen/Core>

#include "io/triangle_mesh.h"

namespace nfield::io {

struct SurfaceComponents {
  int count = 0;                  // connected pieces; 0 for a mesh without triangles
  double area = 0;                // of the whole surface
  double largest_area_share = 0;  // the largest piece's area over `area`; 0 without triangles
  Eigen::VectorXi piece;          // per triangle: its piece, 0 the largest, by area
};

SurfaceComponents surface_components(const TriangleMesh& mesh);

}  // namespace nfield::io
