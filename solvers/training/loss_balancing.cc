// SPDX-License-Identifier: MIT
#include "solvers/training/loss_balancing.h"

#include <algorithm>
#include <cmath>
#include <numeric>


namespace nfield::solvers {

double grad_norm_target(const Eigen::Ref<const Eigen::VectorXd>& pde_gradient,
                        const Eigen::Ref<const Eigen::VectorXd>& term_gradient, double weight,
                        double current) {
  const double mean = term_gradient.size() > 0 ? term_gradient.cwiseAbs().mean() : 0.0;
  const double max = pde_gradient.size() > 0 ? pde_gradient.cwiseAbs().maxCoeff() : 0.0;
  if (!(mean > 0) || !(weight > 0) || !std::isfinite(mean) || !std::isfinite(max)) return current;
  return weight * max / mean;
}

double CausalWeights::min_weight() const {
  return weights.empty() ? 1.0 : *std::min_element(weights.begin(), weights.end());
}

CausalWeights causal_weights(const Eigen::Ref<const Eigen::VectorXd>& times,
                             const Eigen::Ref<const Eigen::VectorXd>& squared_residuals,
                             double t0, double t1, int slices, double epsilon) {
  const Eigen::Index n = times.size();
  std::vector<int> slice(n);
  std::vector<long> counts(slices, 0);
  CausalWeights out;
  out.slice_losses.assign(slices, 0.0);
  for (Eigen::Index p = 0; p < n; ++p) {
    const double s = std::floor((times(p) - t0) / (t1 - t0) * slices);
    slice[p] = static_cast<int>(std::clamp(s, 0.0, slices - 1.0));
    ++counts[slice[p]];
    out.slice_losses[slice[p]] += squared_residuals(p);
  }
  for (int i = 0; i < slices; ++i)
    if (counts[i] > 0) out.slice_losses[i] /= static_cast<double>(counts[i]);
  out.weights.resize(slices);
  double cumulative = 0;
  for (int i = 0; i < slices; ++i) {
    out.weights[i] = std::exp(-epsilon * cumulative);
    cumulative += out.slice_losses[i];
  }
  out.point_weights.resize(n);
  for (Eigen::Index p = 0; p < n; ++p)
    out.point_weights(p) = static_cast<double>(n) * out.weights[slice[p]] /
                           (static_cast<double>(slices) * static_cast<double>(counts[slice[p]]));
  return out;
}

std::vector<Eigen::Index> largest(const Eigen::Ref<const Eigen::VectorXd>& scores, Eigen::Index count) {
  std::vector<Eigen::Index> order(scores.size());
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  count = std::min<Eigen::Index>(count, scores.size());
  // NaN scores sort last: a point where the residual is undefined is no refinement target.
  auto score = [&](Eigen::Index i) { return std::isnan(scores(i)) ? -INFINITY : scores(i); };
  std::partial_sort(order.begin(), order.begin() + count, order.end(),
                    [&](Eigen::Index a, Eigen::Index b) {
                      return score(a) > score(b) || (score(a) == score(b) && a < b);
                    });
  order.resize(count);
  return order;
}

void append_capped(Eigen::MatrixXd& set, const Eigen::MatrixXd& rows, Eigen::Index max_rows) {
  Eigen::MatrixXd joined(set.rows() + rows.rows(), rows.cols());
  if (set.rows() > 0) joined.topRows(set.rows()) = set;
  joined.bottomRows(rows.rows()) = rows;
  const Eigen::Index keep = std::min(max_rows, joined.rows());
  set = joined.bottomRows(keep);
}

}  // namespace nfield::solvers
