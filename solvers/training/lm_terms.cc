// SPDX-License-Identifier: MIT
#include "solvers/training/lm_terms.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "solvers/training/dense_algebra.h"

namespace nfield::solvers {
namespace {

// Jacobian entries per chunk of points in the normal equations (2²⁴ doubles: 128 MiB): a
// chunk's rows go into JᵀJ before the next chunk's are computed.
constexpr double kChunkEntries = 1 << 24;

}  // namespace

template <typename Scalar>
TermCost<Scalar>::TermCost(const fields::Field<Scalar>& network, const LeastSquaresTerm<Scalar>& term,
                           Communicator& communicator)
    : network_(network), layout_(*term.layout), points_(*term.points), communicator_(communicator),
      share_(share_of(points_.rows(), communicator.rank(), communicator.size())),
      residual_(*term.residual, term.weight, points_.rows(), share_.first) {
  this->set_num_residuals(static_cast<int>(points_.rows() * residual_.components()));
  this->mutable_parameter_block_sizes()->push_back(static_cast<int>(network.parameter_count()));
}

template <typename Scalar>
bool TermCost<Scalar>::Evaluate(double const* const* parameters, double* residuals,
                                double** jacobians) const {
  const Eigen::Index m = this->num_residuals(), p = network_.parameter_count();
  double* jacobian = jacobians ? jacobians[0] : nullptr;
  if (communicator_.size() == 1) {
    evaluate_rows(parameters[0], residuals, jacobian);
  } else {
    const std::size_t c = residual_.components();
    std::vector<std::size_t> rows(communicator_.size()), entries(communicator_.size());
    for (int r = 0; r < communicator_.size(); ++r) {
      rows[r] = c * share_of(points_.rows(), r, communicator_.size()).count;
      entries[r] = rows[r] * static_cast<std::size_t>(p);
    }
    mine_r_.resize(static_cast<Eigen::Index>(rows[communicator_.rank()]));
    if (jacobian) mine_j_.resize(static_cast<Eigen::Index>(entries[communicator_.rank()]));
    evaluate_rows(parameters[0], mine_r_.data(), jacobian ? mine_j_.data() : nullptr);
    communicator_.allgather(mine_r_.data(), rows, residuals);
    if (jacobian) communicator_.allgather(mine_j_.data(), entries, jacobian);
  }
  const Eigen::Map<const Eigen::VectorXd> r(residuals, m);
  if (!r.allFinite()) return false;
  if (jacobian) {
    if (!Eigen::Map<const Eigen::VectorXd>(jacobian, m * p).allFinite()) return false;
    // A trust-region method evaluates Jacobians only at its iterates.
    loss_at_iterate_ = r.squaredNorm();
  }
  return true;
}

template <typename Scalar>
double TermCost<Scalar>::loss_at(const double* theta) const {
  Eigen::VectorXd r(this->num_residuals());
  const double* parameters[] = {theta};
  return Evaluate(parameters, r.data(), nullptr) ? r.squaredNorm() : NAN;
}

// The residuals and Jacobian rows of this rank's points (all of them with one rank).
template <typename Scalar>
void TermCost<Scalar>::evaluate_rows(const double* theta, double* residuals, double* jacobian) const {
  if (share_.count == 0) return;
  const Eigen::Index m = share_.count * residual_.components(), p = network_.parameter_count();
  const autodiff::Batch<Scalar> batch{points_.middleRows(share_.first, share_.count)};
  if constexpr (std::is_same_v<Scalar, double>) {
    network_.residuals_and_jacobian(theta, layout_, batch, residual_, residuals, jacobian);
  } else {
    theta_ = Eigen::Map<const Eigen::VectorXd>(theta, p).cast<Scalar>();
    r_.resize(m);
    if (jacobian) j_.resize(m * p);
    network_.residuals_and_jacobian(theta_.data(), layout_, batch, residual_, r_.data(),
                                    jacobian ? j_.data() : nullptr);
    Eigen::Map<Eigen::VectorXd>(residuals, m) = r_.template cast<double>();
    if (jacobian) Eigen::Map<Eigen::VectorXd>(jacobian, m * p) = j_.template cast<double>();
  }
}

template <typename Scalar>
TermsNormalEquations<Scalar>::TermsNormalEquations(const fields::Field<Scalar>& network,
                                                   std::vector<LeastSquaresTerm<Scalar>> terms,
                                                   Communicator& communicator, int threads,
                                                   TrainedUnknowns<Scalar>* unknowns)
    : network_(network), unknowns_(unknowns && unknowns->active() ? unknowns : nullptr), terms_(std::move(terms)), communicator_(communicator), threads_(threads),
      losses_at_iterate_(terms_.size(), NAN), losses_at_trial_(terms_.size(), NAN) {}

template <typename Scalar>
void TermsNormalEquations<Scalar>::set_theta(const Eigen::VectorXd& theta) {
  theta_ = theta.cast<Scalar>();
  if (unknowns_) unknowns_->before_pass(theta_.data());
}

template <typename Scalar>
void TermsNormalEquations<Scalar>::add_unknown_columns(const LeastSquaresTerm<Scalar>& term,
                                                       const autodiff::Batch<Scalar>& batch,
                                                       const ScaledResidual<Scalar>& residual, Eigen::Index m) {
  if (!unknowns_ || residual.extra_parameters() == 0) return;
  autodiff::Streams<Scalar> out;
  network_.evaluate(theta_.data(), *term.layout, batch, out);
  autodiff::Matrix<Scalar> columns;
  residual.extra_jacobian(0, *term.layout, out, columns);
  const Eigen::Index p = parameter_count(), n = network_.network_parameter_count();
  const UnknownConstants& c = *unknowns_->constants();
  for (Eigen::Index row = 0; row < m; ++row)
    for (int i = 0; i < c.count(); ++i)
      j_(row * p + n + i) = static_cast<Scalar>(static_cast<double>(columns(row, i)) * c.raw_derivative(i));
}

template <typename Scalar>
double TermsNormalEquations<Scalar>::add_term(std::size_t k, Eigen::MatrixXd* jtj,
                                              Eigen::VectorXd* jtf) {
  const LeastSquaresTerm<Scalar>& term = terms_[k];
  const Share share = share_of(term.points->rows(), communicator_.rank(), communicator_.size());
  const Eigen::Index c = term.residual->components(), p = parameter_count();
  // Without a Jacobian, one pass over the share; with one, chunks of points.
  const Eigen::Index chunk =
      jtj ? std::max<Eigen::Index>(1, static_cast<Eigen::Index>(kChunkEntries / double(c * p)))
          : std::max<Eigen::Index>(1, share.count);
  double loss = 0;
  for (Eigen::Index first = 0; first < share.count; first += chunk) {
    const Eigen::Index n = std::min(chunk, share.count - first), m = n * c;
    const ScaledResidual<Scalar> residual(*term.residual, term.weight, term.points->rows(),
                                          share.first + first);
    const autodiff::Batch<Scalar> batch{term.points->middleRows(share.first + first, n)};
    r_.resize(m);
    if (jtj) j_.resize(m * p);
    network_.residuals_and_jacobian(theta_.data(), *term.layout, batch, residual, r_.data(),
                                    jtj ? j_.data() : nullptr);
    if (jtj) add_unknown_columns(term, batch, residual, m);
    const double* f = nullptr;
    const double* rows = nullptr;
    if constexpr (std::is_same_v<Scalar, double>) {
      f = r_.data();
      rows = j_.data();
    } else {
      r_d_ = r_.template cast<double>();
      f = r_d_.data();
      if (jtj) {
        rows_d_ = j_.template cast<double>();
        rows = rows_d_.data();
      }
    }
    loss += Eigen::Map<const Eigen::VectorXd>(f, m).squaredNorm();
    if (jtj) {
      const dense::BlasThreads threads(threads_, p);
      dense::add_gram(*jtj, rows, m);
      dense::add_transposed_product(*jtf, rows, m, f);
    }
  }
  return loss;
}

template <typename Scalar>
double TermsNormalEquations<Scalar>::cost(const Eigen::VectorXd& theta) {
  set_theta(theta);
  for (std::size_t k = 0; k < terms_.size(); ++k) losses_at_trial_[k] = add_term(k, nullptr, nullptr);
  communicator_.allreduce_sum(losses_at_trial_.data(), losses_at_trial_.size());
  double sum = 0;
  for (double loss : losses_at_trial_) sum += loss;
  return 0.5 * sum;
}

template <typename Scalar>
double TermsNormalEquations<Scalar>::normal_equations(const Eigen::VectorXd& theta,
                                                      Eigen::MatrixXd& jtj, Eigen::VectorXd& jtf) {
  const Eigen::Index p = parameter_count();
  const std::size_t terms = terms_.size();
  set_theta(theta);
  jtj.setZero(p, p);
  jtf.setZero(p);
  for (std::size_t k = 0; k < terms; ++k) losses_at_iterate_[k] = add_term(k, &jtj, &jtf);
  if (communicator_.size() > 1) {
    // One reduction: JᵀJ's upper triangle by columns, then Jᵀf, then the term losses.
    packed_.resize(p * (p + 1) / 2 + p + static_cast<Eigen::Index>(terms));
    Eigen::Index at = 0;
    for (Eigen::Index j = 0; j < p; at += j + 1, ++j) packed_.segment(at, j + 1) = jtj.col(j).head(j + 1);
    packed_.segment(at, p) = jtf;
    for (std::size_t k = 0; k < terms; ++k) packed_(at + p + k) = losses_at_iterate_[k];
    communicator_.allreduce_sum(packed_.data(), static_cast<std::size_t>(packed_.size()));
    at = 0;
    for (Eigen::Index j = 0; j < p; at += j + 1, ++j) jtj.col(j).head(j + 1) = packed_.segment(at, j + 1);
    jtf = packed_.segment(at, p);
    for (std::size_t k = 0; k < terms; ++k) losses_at_iterate_[k] = packed_(at + p + k);
  }
  double sum = 0;
  for (double loss : losses_at_iterate_) sum += loss;
  return 0.5 * sum;
}

template class TermCost<float>;
template class TermCost<double>;
template class TermsNormalEquations<float>;
template class TermsNormalEquations<double>;

}  // namespace nfield::solvers
