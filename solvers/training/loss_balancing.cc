// SPDX-License-Identifier: MIT
#include "solvers/training/loss_balancing.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "solvers/core/problem.h"

namespace nfield::solvers {

AdaptiveOptions adaptive_from_config(const io::ConfigNode& training) {
  AdaptiveOptions o;
  if (!training.has("adaptive")) return o;
  const io::ConfigNode a = training.child("adaptive");
  a.require(a.is_map(), "expected a mapping such as {every: 500, candidates: 10000, add: 100}");
  o.enabled = true;
  if (a.has("every")) o.every = a.get_in_range("every", 1, 1 << 30);
  if (a.has("candidates")) o.candidates = a.get_in_range<long>("candidates", 1, 1L << 24);
  if (a.has("add")) o.add = a.get_in_range<long>("add", 1, o.candidates);
  a.require("add", o.add <= o.candidates, "expected add <= candidates");
  o.max_points = a.has("max_points") ? a.get_in_range<long>("max_points", o.add, 1L << 26)
                                     : std::max(o.max_points, o.add);
  a.reject_unknown_keys();
  return o;
}

BalanceOptions balance_from_config(const io::ConfigNode& training) {
  BalanceOptions o;
  if (!training.has("balance")) return o;
  if (training.has_map("balance")) {
    const io::ConfigNode b = training.child("balance");
    o.method = b.get_choice("method", {"fixed", "grad_norm"});
    if (b.has("every")) o.every = b.get_in_range("every", 1, 1 << 30);
    if (b.has("alpha")) o.alpha = b.get_in_range("alpha", 0.0, 1.0);
    b.require("alpha", o.alpha > 0, "expected alpha in (0, 1]");
    b.reject_unknown_keys();
  } else {
    o.method = training.get_choice("balance", {"fixed", "grad_norm"});
  }
  return o;
}

CausalOptions causal_from_config(const io::ConfigNode& training) {
  CausalOptions o;
  if (!training.has("causal")) return o;
  const io::ConfigNode c = training.child("causal");
  c.require(c.is_map(), "expected a mapping such as {epsilon: 1.0, slices: 32}");
  o.enabled = true;
  if (c.has("epsilon")) o.epsilon = c.get_in_range("epsilon", 0.0, 1e12);
  if (c.has("slices")) o.slices = c.get_in_range("slices", 1, 1 << 16);
  if (c.has("every")) o.every = c.get_in_range("every", 1, 1 << 30);
  c.reject_unknown_keys();
  return o;
}

void write_yaml(YAML::Node& n, const AdaptiveOptions& adaptive, const BalanceOptions& balance,
                const CausalOptions& causal) {
  if (adaptive.enabled) {
    n["adaptive"]["every"] = adaptive.every;
    n["adaptive"]["candidates"] = adaptive.candidates;
    n["adaptive"]["add"] = adaptive.add;
    n["adaptive"]["max_points"] = adaptive.max_points;
  }
  if (balance.method == "fixed") {
    n["balance"] = balance.method;
  } else {
    n["balance"]["method"] = balance.method;
    n["balance"]["every"] = balance.every;
    n["balance"]["alpha"] = io::yaml_number(balance.alpha);
  }
  if (causal.enabled) {
    n["causal"]["epsilon"] = io::yaml_number(causal.epsilon);
    n["causal"]["slices"] = causal.slices;
    n["causal"]["every"] = causal.every;
  }
}

void check_against_problem(const io::ConfigNode& training, const AdaptiveOptions& adaptive,
                           const BalanceOptions& balance, const CausalOptions& causal,
                           const Problem& problem) {
  const bool has_pde = problem.residual_term() >= 0;
  const char* const no_pde = "this problem has no PDE residual term to act on";
  if (adaptive.enabled && !has_pde) throw training.error("adaptive", no_pde);
  if (balance.method == "grad_norm" && !has_pde) throw training.error("balance", no_pde);
  if (causal.enabled && !has_pde) throw training.error("causal", no_pde);
  if (causal.enabled && !problem.domain().has_time())
    throw training.error("causal", "causal weighting needs a time axis (domain.time: [t0, t1])");
}

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
