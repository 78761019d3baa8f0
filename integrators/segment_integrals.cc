// SPDX-License-Identifier: MIT
#include "integrators/segment_integrals.h"

#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nfield::integrators {
namespace {

// The 15 Kronrod nodes on [-1, 1] with their K15 and G7 weights (G7 is 0 off its nodes).
struct Rule {
  Eigen::Matrix<double, 15, 1> nodes, kronrod, gauss;
  Rule() {
    const auto& x = boost::math::quadrature::gauss_kronrod<double, 15>::abscissa();
    const auto& wk = boost::math::quadrature::gauss_kronrod<double, 15>::weights();
    const auto& wg = boost::math::quadrature::gauss<double, 7>::weights();
    gauss.setZero();
    // Boost lists the non-negative half, x[0] = 0; the Gauss nodes are the even entries.
    nodes(7) = 0;
    kronrod(7) = wk[0];
    gauss(7) = wg[0];
    for (int i = 1; i < 8; ++i) {
      nodes(7 - i) = -x[i];
      nodes(7 + i) = x[i];
      kronrod(7 - i) = kronrod(7 + i) = wk[i];
      if (i % 2 == 0) gauss(7 - i) = gauss(7 + i) = wg[i / 2];
    }
  }
};

struct Piece {
  Eigen::Index segment;
  double from, to;  // in [0, 1] along the segment
  int depth;
};

}  // namespace

Eigen::VectorXd antiderivative_differences(const PointFunction& phi, const Eigen::MatrixXd& a,
                                           const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    throw std::invalid_argument("antiderivative_differences: a and b differ in shape");
  Eigen::MatrixXd ends(2 * a.rows(), a.cols());
  ends << a, b;
  const Eigen::VectorXd values = phi(ends);
  return values.tail(a.rows()) - values.head(a.rows());
}

void AdaptiveQuadratureOptions::validate() const {
  if (!(tolerance > 0))
    throw std::invalid_argument("AdaptiveQuadratureOptions.tolerance = " + std::to_string(tolerance) +
                                ": must be > 0");
  if (!(epsilon > 0 && epsilon < 1))
    throw std::invalid_argument("AdaptiveQuadratureOptions.epsilon = " + std::to_string(epsilon) +
                                ": must be in (0, 1)");
  if (max_depth < 1 || max_depth > 60)
    throw std::invalid_argument("AdaptiveQuadratureOptions.max_depth = " + std::to_string(max_depth) +
                                ": must be in [1, 60]");
}

AdaptiveQuadratureResult adaptive_gauss_kronrod(const PointFunction& f, const Eigen::MatrixXd& a,
                                                const Eigen::MatrixXd& b,
                                                const AdaptiveQuadratureOptions& options) {
  options.validate();
  if (a.rows() != b.rows() || a.cols() != b.cols())
    throw std::invalid_argument("adaptive_gauss_kronrod: a and b differ in shape");
  static const Rule rule;
  const Eigen::Index m = a.rows(), d = a.cols();
  const Eigen::MatrixXd span = b - a;
  const Eigen::VectorXd lengths = span.rowwise().norm();

  AdaptiveQuadratureResult result;
  result.integrals = Eigen::VectorXd::Zero(m);
  result.error_estimates = Eigen::VectorXd::Zero(m);
  std::vector<Piece> open;
  open.reserve(static_cast<size_t>(m));
  for (Eigen::Index k = 0; k < m; ++k)
    if (lengths(k) > 0) open.push_back({k, 0.0, 1.0, 0});

  while (!open.empty()) {
    const auto pieces = static_cast<Eigen::Index>(open.size());
    Eigen::MatrixXd points(15 * pieces, d);
    for (Eigen::Index p = 0; p < pieces; ++p) {
      const Piece& piece = open[static_cast<size_t>(p)];
      const double middle = 0.5 * (piece.from + piece.to), half = 0.5 * (piece.to - piece.from);
      for (int i = 0; i < 15; ++i)
        points.row(15 * p + i) = a.row(piece.segment) + (middle + half * rule.nodes(i)) * span.row(piece.segment);
    }
    const Eigen::VectorXd values = f(points);
    if (values.size() != points.rows())
      throw std::invalid_argument("adaptive_gauss_kronrod: the integrand gave " + std::to_string(values.size()) +
                                  " values for " + std::to_string(points.rows()) + " points");
    result.evaluations += points.rows();
    ++result.rounds;

    std::vector<Piece> next;
    for (Eigen::Index p = 0; p < pieces; ++p) {
      const Piece& piece = open[static_cast<size_t>(p)];
      const double scale = 0.5 * (piece.to - piece.from) * lengths(piece.segment);
      const auto v = values.segment<15>(15 * p);
      const double kronrod = scale * rule.kronrod.dot(v), gauss = scale * rule.gauss.dot(v);
      const double estimate = std::abs(kronrod - gauss);
      const double allowed = options.tolerance * (piece.to - piece.from);
      const double rounding = 50 * options.epsilon * std::abs(scale) * rule.kronrod.dot(v.cwiseAbs());
      if (estimate <= allowed || estimate <= rounding || piece.depth >= options.max_depth || !std::isfinite(estimate)) {
        result.integrals(piece.segment) += kronrod;
        result.error_estimates(piece.segment) += estimate;
        if (!(estimate <= allowed)) ++result.unconverged;
      } else {
        const double middle = 0.5 * (piece.from + piece.to);
        next.push_back({piece.segment, piece.from, middle, piece.depth + 1});
        next.push_back({piece.segment, middle, piece.to, piece.depth + 1});
      }
    }
    open.swap(next);
    if (options.on_round) options.on_round(result, static_cast<long>(open.size()));
  }
  return result;
}

}  // namespace nfield::integrators
