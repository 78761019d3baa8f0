// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_residual.h"

#include <ceres/jet.h>

#include <stdexcept>
#include <string>

namespace nfield::solvers {

ExpressionResidual::ExpressionResidual(std::shared_ptr<const io::CompiledExpression> expression,
                                       std::shared_ptr<const std::vector<std::vector<SymbolTerm>>> symbols,
                                       Eigen::MatrixXd points, std::shared_ptr<const UnknownConstants> unknowns,
                                       std::vector<int> reads)
    : expression_(std::move(expression)),
      symbols_(std::move(symbols)),
      points_(std::move(points)),
      unknowns_(std::move(unknowns)),
      reads_(std::move(reads)),
      varying_(expression_->varying_from(static_cast<int>(points_.cols()))) {
  if (!reads_.empty() && !unknowns_) throw std::invalid_argument("a residual reads unknown constants but has none");
  if (static_cast<int>(reads_.size()) > kMaxExpressionReads)
    throw std::invalid_argument("a residual expression reads at most " + std::to_string(kMaxExpressionReads) +
                                " unknown constants");
  const auto n = static_cast<int>(symbols_->size());
  if (n < 1 || n > kMaxExpressionReads)
    throw std::invalid_argument("a residual expression reads 1 to " + std::to_string(kMaxExpressionReads) +
                                " derivative symbols, got " + std::to_string(n));
  if (expression_->row_size() > static_cast<int>(points_.cols() + n + reads_.size()))
    throw std::invalid_argument("residual expression '" + expression_->text() + "' reads a slot beyond " +
                                "the coordinates and symbols");
}

double ExpressionResidual::symbol(int k, Eigen::Index point, const Streams<double>& out) const {
  double value = 0;
  for (const SymbolTerm& t : (*symbols_)[static_cast<std::size_t>(k)])
    value += t.coefficient * out.data(t.stream * out.points + point, t.channel);
  return value;
}

void ExpressionResidual::evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                                  Eigen::MatrixXd& r) const {
  (void)layout;
  std::vector<double> scratch;
  evaluate_into(first, out, r, scratch);
}

void ExpressionResidual::evaluate_into(Eigen::Index first, const Streams<double>& out, Eigen::MatrixXd& r,
                                       std::vector<double>& scratch) const {
  const Eigen::Index n = out.points, d = points_.cols();
  const auto count = static_cast<int>(symbols_->size());
  const auto extra = static_cast<Eigen::Index>(reads_.size());
  Eigen::MatrixXd inputs(n, d + count + extra);
  inputs.leftCols(d) = points_.middleRows(first, n);
  for (Eigen::Index j = 0; j < extra; ++j) inputs.col(d + count + j).setConstant(unknowns_->value(reads_[j]));
  for (int k = 0; k < count; ++k) {
    auto column = inputs.col(d + k);
    column.setZero();
    for (const SymbolTerm& t : (*symbols_)[static_cast<std::size_t>(k)])
      column += t.coefficient * out.data.block(t.stream * n, t.channel, n, 1);
  }
  r.resize(n, 1);
  expression_->evaluate<double>(n, inputs.data(), n, r.data(), scratch);
}

template <int M>
void ExpressionResidual::backward_jet(Eigen::Index first, const Streams<double>& out, const Eigen::MatrixXd& r_bar,
                                      Streams<double>& adjoint) const {
  using Jet = ceres::Jet<double, M>;
  const Eigen::Index n = out.points, d = points_.cols();
  const auto count = static_cast<int>(symbols_->size());
  // The instructions that read no symbol (a source term) once in double over the block.
  Eigen::MatrixXd r;
  std::vector<double> fixed;
  evaluate_into(first, out, r, fixed);
  std::vector<Jet> row(static_cast<std::size_t>(d + count) + reads_.size()), scratch;
  for (std::size_t j = 0; j < reads_.size(); ++j)
    row[static_cast<std::size_t>(d + count) + j] = Jet(unknowns_->value(reads_[j]));
  for (Eigen::Index p = 0; p < n; ++p) {
    // (The coordinates, slots 0 … d − 1, are read from the double pass.)
    for (int k = 0; k < count; ++k) row[static_cast<std::size_t>(d + k)] = Jet(symbol(k, p, out), k);
    const Jet y = expression_->evaluate_varying<Jet>(row.data(), varying_, fixed.data() + p, n, scratch);
    for (int k = 0; k < count; ++k) {
      const double g = r_bar(p, 0) * y.v[k];
      for (const SymbolTerm& t : (*symbols_)[static_cast<std::size_t>(k)])
        adjoint.data(t.stream * n + p, t.channel) += t.coefficient * g;
    }
  }
}

template <int M>
void ExpressionResidual::extra_jet(Eigen::Index first, const Streams<double>& out, Eigen::MatrixXd& jacobian) const {
  using Jet = ceres::Jet<double, M>;
  const Eigen::Index n = out.points, d = points_.cols();
  const auto count = static_cast<int>(symbols_->size());
  Eigen::MatrixXd r;
  std::vector<double> fixed;
  evaluate_into(first, out, r, fixed);
  jacobian.setZero(n, unknowns_->count());
  std::vector<Jet> row(static_cast<std::size_t>(d + count) + reads_.size()), scratch;
  for (std::size_t j = 0; j < reads_.size(); ++j)
    row[static_cast<std::size_t>(d + count) + j] = Jet(unknowns_->value(reads_[j]), static_cast<int>(j));
  for (Eigen::Index p = 0; p < n; ++p) {
    for (int k = 0; k < count; ++k) row[static_cast<std::size_t>(d + k)] = Jet(symbol(k, p, out));
    const Jet y = expression_->evaluate_varying<Jet>(row.data(), varying_, fixed.data() + p, n, scratch);
    for (std::size_t j = 0; j < reads_.size(); ++j) jacobian(p, reads_[j]) += y.v[j];
  }
}

void ExpressionResidual::extra_jacobian(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                                        Eigen::MatrixXd& jacobian) const {
  (void)layout;
  const std::size_t count = reads_.size();
  if (count == 0) return jacobian.setZero(out.points, 0), void();
  if (count <= 1) return extra_jet<1>(first, out, jacobian);
  if (count <= 2) return extra_jet<2>(first, out, jacobian);
  if (count <= 4) return extra_jet<4>(first, out, jacobian);
  if (count <= 8) return extra_jet<8>(first, out, jacobian);
  if (count <= 16) return extra_jet<16>(first, out, jacobian);
  extra_jet<kMaxExpressionReads>(first, out, jacobian);
}

void ExpressionResidual::backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                                  const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const {
  (void)layout;
  const auto count = static_cast<int>(symbols_->size());
  if (count <= 1) return backward_jet<1>(first, out, r_bar, adjoint);
  if (count <= 2) return backward_jet<2>(first, out, r_bar, adjoint);
  if (count <= 4) return backward_jet<4>(first, out, r_bar, adjoint);
  if (count <= 8) return backward_jet<8>(first, out, r_bar, adjoint);
  if (count <= 16) return backward_jet<16>(first, out, r_bar, adjoint);
  backward_jet<kMaxExpressionReads>(first, out, r_bar, adjoint);
}

}  // namespace nfield::solvers
