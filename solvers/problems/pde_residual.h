// SPDX-License-Identifier: MIT
//
// The residual of `problem: pde`: one compiled expression (io/compiled_expression.h) over a
// point's coordinates and the derivative symbols it reads (solvers/problems/pde_streams.h),
//
//   r(xₙ) = e(xₙ, s₁(xₙ), …, s_N(xₙ)),   s_k = Σ_j c_kj · out[stream_kj][channel_kj] at xₙ,
//
// each symbol a fixed linear combination of stream entries (one entry for a value, a
// gradient component or an operator stream; several for a polarized Taylor derivative).
//
//   evaluate   e in double over the block: the coordinates and symbols as the columns of one
//              n × (d + N) matrix, the tape run once per instruction over the block;
//   backward   e per point in ceres::Jet<double, M>, the symbols seeded as unit duals and the
//              coordinates as constants, so y.v[k] = ∂r/∂s_k (the instructions that read no
//              symbol, a source term, are taken from a pass in double over the block), and
//              adjoint[stream_kj][channel_kj] += c_kj · r̄ₙ · ∂r/∂s_k:
//              the contract of Residual::backward, with no adjoint written by hand.
//
// Unknown constants (solvers/core/unknowns.h) the expression reads are slots d + N + j after the
// symbols, filled with their current values at every evaluation (no re-parsing); their
// Jacobian ∂r/∂c (extra_jacobian) is one more Jet pass with the constants seeded as the duals
// and the symbols held constant.
//
// N is known only when the config is read, so M is the smallest of 1, 2, 4, 8, 16, 32 at
// least N (a few unused dual slots cost nothing next to the network); a residual may read at
// most kMaxExpressionReads symbols. As in solvers/core/jet_residual.h, what Jet calls a derivative
// at a kink (abs at 0, min/max at a tie, sqrt at 0) is the branch taken or an infinity.
#pragma once

#include <memory>
#include <vector>

#include "io/compiled_expression.h"
#include "solvers/problems/pde_streams.h"
#include "solvers/core/residual.h"
#include "solvers/core/unknowns.h"

namespace nfield::solvers {

inline constexpr int kMaxExpressionReads = 32;

class ExpressionResidual final : public Residual {
 public:
  // `expression` reads slot a < d as coordinate a of a point (the rows of `points`, d its
  // columns) and slot d + k as symbol k, whose stream entries are symbols[k].
  // `reads[j]` is the unknown constant (an index of `unknowns`) at slot d + N + j.
  ExpressionResidual(std::shared_ptr<const io::CompiledExpression> expression,
                     std::shared_ptr<const std::vector<std::vector<SymbolTerm>>> symbols,
                     Eigen::MatrixXd points, std::shared_ptr<const UnknownConstants> unknowns = nullptr,
                     std::vector<int> reads = {});

  int components() const override { return 1; }
  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override;
  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override;
  int extra_parameters() const override { return reads_.empty() ? 0 : unknowns_->count(); }
  void extra_jacobian(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                      Eigen::MatrixXd& jacobian) const override;

 private:
  double symbol(int k, Eigen::Index point, const Streams<double>& out) const;
  // r over the block, keeping the registers of the tape (n per instruction) in `scratch`.
  void evaluate_into(Eigen::Index first, const Streams<double>& out, Eigen::MatrixXd& r,
                     std::vector<double>& scratch) const;
  template <int M>
  void backward_jet(Eigen::Index first, const Streams<double>& out, const Eigen::MatrixXd& r_bar,
                    Streams<double>& adjoint) const;
  template <int M>
  void extra_jet(Eigen::Index first, const Streams<double>& out, Eigen::MatrixXd& jacobian) const;

  std::shared_ptr<const io::CompiledExpression> expression_;
  std::shared_ptr<const std::vector<std::vector<SymbolTerm>>> symbols_;
  Eigen::MatrixXd points_;
  std::shared_ptr<const UnknownConstants> unknowns_;
  std::vector<int> reads_;
  std::vector<char> varying_;  // the instructions that read a symbol (the rest: from a double pass)
};

}  // namespace nfield::solvers
