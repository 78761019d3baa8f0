// SPDX-License-Identifier: MIT
//
// The `data:` section of `problem: pde`: measurements of the solution, fitted by one loss
// term `data` beside the residuals (an inverse problem's evidence: with unknown constants,
// solvers/core/unknowns.h, the term pins the field to the measured solution and the residuals then
// tell the constants).
//
//   data:
//     file: data/burgers.csv        # CSV with a header, a whitespace table (% or # comments)
//                                   # or "F.h5:/dataset": read as reference.file is
//                                   # (solvers/problems/pde_reference.h), relative to the config
//     columns: {t: time, u: u_obs}  # variable or output → column name (default: the same)
//     outputs: [u]                  # the outputs measured (default: all); columns of these only
//     weight: 1                     # the term's weight, or
//     sigma: 0.01                   # the measurements' noise level: weight 1/σ²
//
//   data:
//     exact:                        # synthetic measurements, for studies and tests
//       u: "sin(pi*x)*exp(-t)"      # an expression per measured output, or `reference`:
//                                   # the reference's exact or named solution (burgers_sine)
//       points: 2000                # uniform random points of the domain (space × time), or
//       grid: [50, 50]              # a regular grid of a box domain, ends included, one size
//                                   # per input (space, then time; PINNacle's 50 × 50 data)
//       noise: 0.01                 # relative Gaussian noise: u + noise·std(u)·N(0, 1), std
//                                   # over the points per output (Raissi et al. 2019's rule), or
//       noise_std: 0.1              # absolute Gaussian noise: u + 0.1·N(0, 1) (PINNacle's PInv)
//       seed: 1                     # of the points and the noise (Box–Muller on the engine's
//                                   # own uniforms, so the same on every platform)
//
// The term is  L = w/N Σₙ Σ_c (u_c(xₙ) − dₙ_c)², N the measurements, every one of them at
// every step (its points are fixed: it has no training.batch entry). Refused with the
// config's location: a file's missing or non-numeric column, a point outside the domain
// (as reference.file), an output measured twice or unknown, both weight and sigma.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "io/config.h"
#include "solvers/core/domain.h"
#include "solvers/problems/pde_reference.h"
#include "solvers/core/residual.h"

namespace nfield::solvers {

class PdeData {
 public:
  PdeData() = default;
  // `reference`: the problem's reference (for `u: reference`; null when it has none).
  PdeData(const io::ConfigNode& node, const Domain& domain, const std::vector<std::string>& outputs,
          const PdeExpressions& expressions, const PdeReference* reference,
          const std::filesystem::path& config_dir);

  bool empty() const { return points_.rows() == 0; }
  const Eigen::MatrixXd& points() const { return points_; }  // N × input_dim
  const Eigen::MatrixXd& values() const { return values_; }  // N × measured outputs
  const std::vector<int>& measured() const { return measured_; }  // output index per column
  double weight() const { return weight_; }
  // The loss term `data` (empty batch key: it draws all its points every step).
  LossTerm loss_term(int input_dim) const;

  // N points of the domain and each output's values there with relative Gaussian noise
  // (see the header), one output per column of `clean`.
  static Eigen::MatrixXd add_noise(const Eigen::MatrixXd& clean, double noise, Random& rng);
  // `grid:` of data.exact: the points of a regular grid of a box domain (see the header).
  static Eigen::MatrixXd grid_points(const io::ConfigNode& exact, const Domain& domain);

 private:
  void read_exact(const io::ConfigNode& exact, const Domain& domain, const std::vector<std::string>& outputs,
                  const PdeExpressions& expressions, const PdeReference* reference);

  Eigen::MatrixXd points_, values_;
  std::vector<int> measured_;
  double weight_ = 1;
};

}  // namespace nfield::solvers
