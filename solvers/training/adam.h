// SPDX-License-Identifier: MIT
//
// Adam (Kingma and Ba 2015) on a flat parameter vector:
//   m ← β₁ m + (1 − β₁) g,  v ← β₂ v + (1 − β₂) g²,
//   θ ← θ − lr · m̂ / (√v̂ + ε),  m̂ = m / (1 − β₁ᵗ), v̂ = v / (1 − β₂ᵗ).
// The state (m, v, t) is plain data so a checkpoint can save and restore it exactly.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "autodiff/streams.h"

namespace nfield::solvers {

struct AdamOptions {
  double learning_rate = 1e-4;
  double beta1 = 0.9;
  double beta2 = 0.999;
  double epsilon = 1e-8;

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

template <typename Scalar>
class Adam {
 public:
  explicit Adam(Eigen::Index parameter_count, AdamOptions options = {});

  // One update of `params` from `gradient` at the given learning rate (schedules pass theirs).
  void step(Scalar* params, const Scalar* gradient, double learning_rate);
  void step(Scalar* params, const Scalar* gradient) { step(params, gradient, options_.learning_rate); }

  // Parameter i steps at learning_rate · scale (an unknown constant's own `lr`,
  // solvers/core/unknowns.h); the others at learning_rate. Not state: set from the config.
  void set_rate_scale(Eigen::Index i, double scale) {
    for (auto& entry : rate_scales_)
      if (entry.first == i) return void(entry.second = scale);
    rate_scales_.emplace_back(i, scale);
  }

  const AdamOptions& options() const { return options_; }
  autodiff::Vector<Scalar>& first_moment() { return m_; }
  autodiff::Vector<Scalar>& second_moment() { return v_; }
  const autodiff::Vector<Scalar>& first_moment() const { return m_; }
  const autodiff::Vector<Scalar>& second_moment() const { return v_; }
  std::int64_t steps() const { return t_; }
  void set_steps(std::int64_t t) { t_ = t; }

 private:
  AdamOptions options_;
  autodiff::Vector<Scalar> m_, v_;
  std::int64_t t_ = 0;
  std::vector<std::pair<Eigen::Index, double>> rate_scales_;
};

}  // namespace nfield::solvers
