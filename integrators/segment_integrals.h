// SPDX-License-Identifier: MIT
//
// Integrals along straight segments [a, b] of ℝᵈ, two ways.
//
// From an antiderivative (AutoInt, Lindell et al. 2021). If a field Φ has, along the unit
// direction u = (b − a)/‖b − a‖, the derivative ∂ᵤΦ = f, then
//
//     ∫₀^‖b−a‖ f(a + s·u) ds = Φ(b) − Φ(a),
//
// two evaluations of Φ whatever f looks like. ∂ᵤΦ is Φ's tangent stream along u
// (autodiff/streams.h), so training Φ through that stream fits f ("the grad network"), and
// its integrals then cost two value evaluations each.
//
// By adaptive quadrature, the reference: Gauss–Kronrod G7/K15 on each segment (nodes and
// weights from Boost.Math), the estimate |K15 − G7| of a piece compared with the piece's
// share of the tolerance, pieces above it bisected. Unlike one-integral-at-a-time quadrature
// every round evaluates the integrand at the nodes of all open pieces of all segments in one
// batch, so a field is evaluated in large blocks, as it is for the antiderivative.
#pragma once

#include <functional>

#include <Eigen/Core>

namespace nfield::integrators {

// Values of a function at points (n × d) → n values.
using PointFunction = std::function<Eigen::VectorXd(const Eigen::MatrixXd& points)>;

// Φ(b) − Φ(a) per row, ends given as rows of `a` and `b` (m × d).
Eigen::VectorXd antiderivative_differences(const PointFunction& phi, const Eigen::MatrixXd& a,
                                           const Eigen::MatrixXd& b);

struct AdaptiveQuadratureOptions {
  // Absolute error allowed per segment; a piece of length ℓ of a segment of length L may
  // keep an estimate up to tolerance · ℓ / L. > 0.
  double tolerance = 1e-8;
  // Bisections of a segment at most; a piece this deep is accepted as it is (and counted in
  // `unconverged`). 1 … 60.
  int max_depth = 30;
  // Relative rounding error of the integrand's values (the evaluating scalar's epsilon: a
  // float field's values are good to about 1e-7). A piece whose estimate is within
  // 50 · epsilon · ∫|f| over it is accepted: below that, |K15 − G7| measures rounding, not
  // the rule's error, and bisecting further would never end.
  double epsilon = 2.220446049250313e-16;
  // Called after every round with the result so far and the pieces still open (progress
  // lines for long integrations); may be empty.
  std::function<void(const struct AdaptiveQuadratureResult& so_far, long open_pieces)> on_round;

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

struct AdaptiveQuadratureResult {
  Eigen::VectorXd integrals;        // per segment
  Eigen::VectorXd error_estimates;  // Σ |K15 − G7| of the accepted pieces, per segment
  long evaluations = 0;             // integrand values computed, over all segments
  long unconverged = 0;             // pieces accepted above their tolerance (max_depth, rounding)
  int rounds = 0;                   // batches evaluated
};

// ∫ f ds along each segment [a_k, b_k] (rows of a and b, m × d), s the arc length.
AdaptiveQuadratureResult adaptive_gauss_kronrod(const PointFunction& f, const Eigen::MatrixXd& a,
                                                const Eigen::MatrixXd& b,
                                                const AdaptiveQuadratureOptions& options = {});

}  // namespace nfield::integrators
