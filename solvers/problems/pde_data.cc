// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_data.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "io/text.h"

namespace nfield::solvers {

namespace {

int index_of(const std::vector<std::string>& names, const std::string& name) {
  const auto at = std::find(names.begin(), names.end(), name);
  return at == names.end() ? -1 : static_cast<int>(at - names.begin());
}

}  // namespace

PdeData::PdeData(const io::ConfigNode& node, const Domain& domain, const std::vector<std::string>& outputs,
                 const PdeExpressions& expressions, const PdeReference* reference,
                 const std::filesystem::path& config_dir) {
  node.require(node.is_map(), "expected a mapping with file (and columns) or exact");
  if (node.has("weight") && node.has("sigma")) throw node.error("sigma", "give weight or sigma, not both");
  if (node.has("weight")) {
    weight_ = node.get<double>("weight");
    node.require("weight", std::isfinite(weight_) && weight_ > 0, "expected a weight > 0");
  }
  if (node.has("sigma")) {
    const double sigma = node.get<double>("sigma");
    node.require("sigma", std::isfinite(sigma) && sigma > 0, "expected a noise level sigma > 0");
    weight_ = 1 / (sigma * sigma);
  }
  if (node.has("exact")) {
    if (node.has("file")) throw node.error("exact", "give file or exact, not both");
    node.require("outputs", !node.has("outputs"), "exact names the measured outputs by its keys");
    read_exact(node.child("exact"), domain, outputs, expressions, reference);
    node.reject_unknown_keys();
    return;
  }
  node.require(node.has("file"), "expected file (measurements) or exact (synthetic ones)");
  std::vector<std::string> measured = node.get_or<std::vector<std::string>>("outputs", outputs);
  for (const std::string& name : measured) {
    const int c = index_of(outputs, name);
    if (c < 0) throw node.error("outputs", "'" + name + "' is no output (outputs: " + io::join(outputs) + ")");
    if (std::count(measured.begin(), measured.end(), name) > 1)
      throw node.error("outputs", "output '" + name + "' is listed twice");
    measured_.push_back(c);
  }
  // The file's reading, column checks and domain check are reference.file's.
  const PdeReference file(node, domain, measured, expressions, config_dir);
  if (file.files().size() != 1) throw node.error("file", "expected one file of measurements");
  const ReferencePoints& table = file.files().front();
  points_ = table.points;
  values_ = table.values;
  // Column k of the table holds measured output table.outputs[k].
  std::vector<int> columns;
  for (const int k : table.outputs) columns.push_back(measured_[k]);
  measured_ = columns;
}

void PdeData::read_exact(const io::ConfigNode& exact, const Domain& domain, const std::vector<std::string>& outputs,
                         const PdeExpressions& expressions, const PdeReference* reference) {
  exact.require(exact.is_map(), "expected a mapping: an expression per measured output, points or grid, noise "
                                "or noise_std, seed");
  if (exact.has("points") && exact.has("grid")) throw exact.error("grid", "give points or grid, not both");
  if (exact.has("noise") && exact.has("noise_std")) throw exact.error("noise_std", "give noise or noise_std, not both");
  const double noise = exact.get_or("noise", 0.0);
  exact.require("noise", std::isfinite(noise) && noise >= 0, "expected a relative noise level >= 0");
  const double noise_std = exact.get_or("noise_std", 0.0);
  exact.require("noise_std", std::isfinite(noise_std) && noise_std >= 0, "expected a noise standard deviation >= 0");
  const long seed = exact.get_or("seed", 1L);
  exact.require("seed", seed >= 0, "expected a seed >= 0");
  Random rng(static_cast<Random::result_type>(seed));
  if (exact.has("grid")) {
    points_ = grid_points(exact, domain);
  } else {
    const long count = exact.get_or("points", 1000L);
    exact.require("points", count >= 1 && count <= 10000000, "expected a number of points in [1, 1e7]");
    points_ = domain.sample_interior(rng, count);
  }
  const Eigen::Index n = points_.rows();
  std::vector<Eigen::VectorXd> columns;
  for (const std::string& key : exact.keys()) {
    if (key == "points" || key == "grid" || key == "noise" || key == "noise_std" || key == "seed") continue;
    const int c = index_of(outputs, key);
    if (c < 0)
      throw exact.error(key, "'" + key + "' is no output (outputs: " + io::join(outputs) +
                                 "; and points, grid, noise, noise_std, seed)");
    measured_.push_back(c);
    if (io::to_lower(exact.get<std::string>(key)) == "reference") {
      if (!reference || !reference->has_exact())
        throw exact.error(key, "'reference' needs reference.exact or reference.solution");
      columns.push_back(reference->exact(points_).col(c));
      continue;
    }
    const io::CompiledExpression e = expressions.compile(exact, key);
    Eigen::VectorXd v(n);
    std::vector<double> scratch;
    e.evaluate<double>(n, points_.data(), n, v.data(), scratch);
    columns.push_back(v);
  }
  if (measured_.empty()) throw exact.error("expected an expression (or reference) per measured output");
  Eigen::MatrixXd clean(n, static_cast<Eigen::Index>(columns.size()));
  for (std::size_t j = 0; j < columns.size(); ++j) clean.col(static_cast<Eigen::Index>(j)) = columns[j];
  values_ = noise > 0 ? add_noise(clean, noise, rng) : clean;
  if (noise_std > 0)
    for (Eigen::Index c = 0; c < values_.cols(); ++c)
      for (Eigen::Index i = 0; i < n; ++i) values_(i, c) += noise_std * standard_normal(rng);
}

// `grid: [n₁, …]`: a regular grid of a box domain, n per input (space, then time), ends
// included (n ≥ 2), first input fastest.
Eigen::MatrixXd PdeData::grid_points(const io::ConfigNode& exact, const Domain& domain) {
  if (domain.geometry()) throw exact.error("grid", "a grid of measurements needs a box domain (no geometry)");
  const int d = domain.input_dim();
  const std::vector<int> sizes = exact.get<std::vector<int>>("grid");
  exact.require("grid", static_cast<int>(sizes.size()) == d,
                "expected " + std::to_string(d) + " sizes (one per input: the space variables, then time)");
  Eigen::Index total = 1;
  for (const int k : sizes) {
    exact.require("grid", k >= 2 && k <= 100000, "expected sizes in [2, 1e5] (the ends are included)");
    total *= k;
  }
  exact.require("grid", total <= 10000000, "expected at most 1e7 points");
  const Eigen::VectorXd lo = domain.input_lower(), hi = domain.input_upper();
  Eigen::MatrixXd points(total, d);
  for (Eigen::Index i = 0; i < total; ++i) {
    Eigen::Index rest = i;
    for (int a = 0; a < d; ++a) {
      const int k = sizes[static_cast<std::size_t>(a)];
      points(i, a) = lo(a) + (hi(a) - lo(a)) * static_cast<double>(rest % k) / (k - 1);
      rest /= k;
    }
  }
  return points;
}

Eigen::MatrixXd PdeData::add_noise(const Eigen::MatrixXd& clean, double noise, Random& rng) {
  Eigen::MatrixXd noisy = clean;
  for (Eigen::Index c = 0; c < clean.cols(); ++c) {
    const double mean = clean.col(c).mean();
    const double std = std::sqrt((clean.col(c).array() - mean).square().sum() / static_cast<double>(clean.rows()));
    for (Eigen::Index i = 0; i < clean.rows(); ++i) noisy(i, c) += noise * std * standard_normal(rng);
  }
  return noisy;
}

LossTerm PdeData::loss_term(int input_dim) const {
  LossTerm term;
  term.name = "data";
  term.batch_key.clear();
  term.weight = weight_;
  term.spec = autodiff::StreamSpec::values(input_dim);
  term.sample = [points = points_](Random&, Eigen::Index) { return TermPoints(points); };
  std::vector<LinearResidual::Term> terms;
  for (std::size_t j = 0; j < measured_.size(); ++j)
    terms.push_back({static_cast<int>(j), 0, measured_[j], Eigen::VectorXd::Ones(1)});
  term.residual = [terms, values = values_](const TermPoints&) {
    return std::make_unique<LinearResidual>(terms, values);
  };
  return term;
}

}  // namespace nfield::solvers
