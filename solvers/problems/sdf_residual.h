// SPDX-License-Identifier: MIT
//
// The residuals of the sdf problem (sdf.cc, whose header explains them), written once
// through JetResidual (solvers/core/jet_residual.h); here so that the tests can build them on
// data of their own.
#pragma once

#include <memory>

#include "solvers/core/residual.h"

namespace nfield::solvers {

struct SdfWeights {
  double sdf = 3e3, normal = 1e2, eikonal = 5e1, off_surface = 1e2, alpha = 1e2;
  bool absolute = true;  // loss: siren (|u|, ||∇u| − 1|) rather than squares
};

// The "surface" residual (surface: normals n × 3, one row per point of the set; 5
// components) or the "interior" one (normals empty; 2 components). It reads the value and
// the three gradient tangents of channel 0.
std::unique_ptr<Residual> make_sdf_residual(Eigen::MatrixXd normals, bool surface,
                                            const SdfWeights& weights);

}  // namespace nfield::solvers
