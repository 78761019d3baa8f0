// SPDX-License-Identifier: MIT
//
// The least-squares problem of an `lm` stage: the loss terms at their points as N·C residuals
// f = √(w/N)·r each (point-major), over the field's parameters θ, so that ½‖f‖² is half the
// stage's loss. Two forms of it, one per backend of the stage:
//
//   TermCost            one term as a Ceres cost function (backend: ceres). Over R ranks each
//                       computes the rows of its share of the points and gathers the others'
//                       (every rank's Ceres then solves the same whole problem): the network
//                       passes split, the dense solve does not.
//   TermsNormalEquations  all terms as the normal equations of the own LM
//                       (solvers/training/levenberg_marquardt.h, backend: own): the rows of
//                       each term, a chunk of points at a time, go straight into JᵀJ (BLAS
//                       syrk) and Jᵀf (gemv) in double, so no whole Jacobian is ever held. Over
//                       R ranks each forms the sums of its share of the points and one
//                       allreduce adds them (JᵀJ's upper triangle packed, Jᵀf and the term
//                       losses in one buffer: P(P+1)/2 + P + K doubles per rank and iterate);
//                       no Jacobian rows travel. The sums differ from one process's by the
//                       order of additions only.
//
// Jacobian rows come from the reverse pass per point (Sequential::residuals_and_jacobian) in
// the training scalar and are converted to double. An inverse problem's unknown constants
// (solvers/training/trained_unknowns.h) are the last columns of θ: their entries of each row,
// ∂f/∂ρ = ∂f/∂c · dc/dρ, come from the residual's extra_jacobian over a forward pass of the
// chunk (own backend only; the Ceres backend refuses them).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include <vector>

#include "fields/field.h"
#include "solvers/core/residual.h"
#include "solvers/training/communicator.h"
#include "solvers/training/levenberg_marquardt.h"
#include "solvers/training/trained_unknowns.h"

namespace nfield::solvers {

// One loss term of the problem.
template <typename Scalar>
struct LeastSquaresTerm {
  const autodiff::StreamLayout* layout = nullptr;
  const autodiff::Matrix<Scalar>* points = nullptr;  // N × input_dim
  const Residual* residual = nullptr;
  double weight = 1;  // w·λ
};

template <typename Scalar>
class TermCost final : public ceres::CostFunction {
 public:
  TermCost(const fields::Field<Scalar>& network, const LeastSquaresTerm<Scalar>& term,
           Communicator& communicator);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // This term's loss (Σ f²) at the last point where the Jacobian was evaluated.
  double loss_at_iterate() const { return loss_at_iterate_; }
  // Its loss at θ, from a forward pass.
  double loss_at(const double* theta) const;

 private:
  void evaluate_rows(const double* theta, double* residuals, double* jacobian) const;

  const fields::Field<Scalar>& network_;
  const autodiff::StreamLayout& layout_;
  const autodiff::Matrix<Scalar>& points_;
  Communicator& communicator_;
  Share share_;
  ScaledResidual<Scalar> residual_;
  mutable autodiff::Vector<Scalar> theta_, r_, j_;
  mutable Eigen::VectorXd mine_r_, mine_j_;
  mutable double loss_at_iterate_ = NAN;
};

template <typename Scalar>
class TermsNormalEquations final : public NormalEquationsProblem {
 public:
  // `threads`: of the BLAS products (the field's passes use their own setting).
  // `unknowns` (null: none) is kept in step with each θ evaluated.
  TermsNormalEquations(const fields::Field<Scalar>& network,
                       std::vector<LeastSquaresTerm<Scalar>> terms, Communicator& communicator,
                       int threads, TrainedUnknowns<Scalar>* unknowns = nullptr);

  Eigen::Index parameter_count() const override { return network_.parameter_count(); }
  double cost(const Eigen::VectorXd& theta) override;
  double normal_equations(const Eigen::VectorXd& theta, Eigen::MatrixXd& jtj,
                          Eigen::VectorXd& jtf) override;

  // Σ f² of each term at the last θ the normal equations were evaluated at.
  const std::vector<double>& losses_at_iterate() const { return losses_at_iterate_; }
  // The same at the last θ `cost` was evaluated at.
  const std::vector<double>& losses_at_trial() const { return losses_at_trial_; }

 private:
  // Σ f² of term k's rows on this rank; with `jtj` and `jtf`, their sums added there too.
  double add_term(std::size_t k, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtf);
  void set_theta(const Eigen::VectorXd& theta);
  // The unknowns' columns of rows j_ (m rows of parameter_count()) of a chunk.
  void add_unknown_columns(const LeastSquaresTerm<Scalar>& term, const autodiff::Batch<Scalar>& batch,
                           const ScaledResidual<Scalar>& residual, Eigen::Index m);

  const fields::Field<Scalar>& network_;
  TrainedUnknowns<Scalar>* unknowns_;
  std::vector<LeastSquaresTerm<Scalar>> terms_;
  Communicator& communicator_;
  int threads_;
  autodiff::Vector<Scalar> theta_, r_, j_;
  Eigen::VectorXd rows_d_, r_d_, packed_;
  std::vector<double> losses_at_iterate_, losses_at_trial_;
};

}  // namespace nfield::solvers
