// SPDX-License-Identifier: MIT
//
// The residuals of the eikonal problem (eikonal.cc, whose header explains each term),
// written once through JetResidual (solvers/core/jet_residual.h); here so that the tests can
// build every form on points and per-point data of their own.
#pragma once

#include <memory>

#include "solvers/core/residual.h"

namespace nfield::solvers {

// The residuals of the loss terms on one point set; u is the network output (plain) or
// T₀ (1 + τ) (factored):
//   eikonal    r = |∇u| − s(x) − ε·(viscous term), s = 1/v
//   outflow    r = [min(0, ∇u·n), min(0, u)/L] with outward normals n
//   source     r = the output itself (u or τ) at x₀
//   interface  r = max(0, −∇u·n) (1/v_far − |∇u − (∇u·n) n|), n the normal from the source's
//              layer to the far one, on the source's side of the plane
enum class EikonalKind { kEikonal, kOutflow, kSource, kInterface };

struct EikonalSetup {
  bool factored = false;
  Eigen::VectorXd x0;
  double v0 = 1;
  double viscosity = 0;
  bool concave = false;     // the viscous term is ε min(0, Δu) (`viscosity_form: concave`)
  double length = 1;        // L of the outflow term
  double far_slowness = 0;  // 1/v of the layer without the source (interface term)
};

// points: n × d, d = 2 or 3 (std::invalid_argument otherwise). per_point: the slowness s
// (eikonal, n × 1) or the normals (outflow and interface, n × d); unused for the source.
// The eikonal kind with viscosity > 0 reads the Laplacian stream (layout.op(0)).
std::unique_ptr<Residual> make_eikonal_residual(EikonalKind kind, Eigen::MatrixXd points,
                                                Eigen::MatrixXd per_point, EikonalSetup setup);

}  // namespace nfield::solvers
