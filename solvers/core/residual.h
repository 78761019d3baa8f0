// SPDX-License-Identifier: MIT
//
// Residuals: per-point vectors r(x) computed from a field's output streams, and the loss
// terms built from them, L = w · (1/N) Σₙ ‖r(xₙ)‖². Residuals work in double whatever the
// training precision: they read and write only the output streams (width 1 or 2), so the
// conversion costs nothing next to the network.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "autodiff/stream_loss.h"
#include "autodiff/stream_residual.h"
#include "solvers/core/domain.h"

namespace nfield::solvers {

using autodiff::StreamLayout;
using autodiff::Streams;

// The one residual interface (autodiff/stream_residual.h), in double: the trainer's
// adapters below scale it into a loss or a least-squares residual in the training precision.
using Residual = autodiff::StreamResidual<double>;

// r_c = Σₖ aₖ(x) · out[streamₖ][channelₖ] − f_c(x): every linear PDE and condition.
class LinearResidual final : public Residual {
 public:
  struct Term {
    int component = 0;
    int stream = 0;
    int channel = 0;
    Eigen::VectorXd coefficient;  // one per point, or a single value for all
  };
  // source: points × components.
  LinearResidual(std::vector<Term> terms, Eigen::MatrixXd source);

  int components() const override { return static_cast<int>(source_.cols()); }
  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override;
  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override;

 private:
  std::vector<Term> terms_;
  Eigen::MatrixXd source_;
};

// A residual with a version per scale of a multiscale field (HasScaleTargets,
// solvers/core/problem_capabilities.h): at_scale(s) is scale s's, and the plain calls are
// the output scale's (what Levenberg–Marquardt and a single-scale loss read).
class ScaleTargetResidual final : public Residual {
 public:
  ScaleTargetResidual(std::vector<std::unique_ptr<Residual>> scales, int output_scale);

  int components() const override { return output().components(); }
  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    output().evaluate(first, layout, out, r);
  }
  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    output().backward(first, layout, out, r_bar, adjoint);
  }
  int extra_parameters() const override { return output().extra_parameters(); }
  void extra_jacobian(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                      Eigen::MatrixXd& jacobian) const override {
    output().extra_jacobian(first, layout, out, jacobian);
  }
  const Residual& at_scale(int scale) const override;

 private:
  const Residual& output() const { return *scales_[static_cast<size_t>(output_scale_)]; }

  std::vector<std::unique_ptr<Residual>> scales_;
  int output_scale_;
};

// What a loss term draws for one step: the network's inputs x (N × input_dim) and, for a
// term whose residuals each read several points (a pixel's colour reads every sample of its
// ray), the groups: offsets 0 = g₀ ≤ … ≤ g_G = N, group k being rows [g_k, g_{k+1}) of x
// (autodiff::Batch keeps a group inside one block of the pass). `context` carries what such a
// residual needs besides x (the rays' pixel colours, sample spacings); a term that has one
// is drawn anew on resume rather than saved in the checkpoint. `tangents`, when not empty,
// are per-point tangent directions (N × input_dim·T, autodiff::PointTangents) that replace
// the term's StreamSpec::tangents (a ray's direction at each of its samples); T is still
// the number of the spec's tangent columns. A term over single points returns just the
// matrix, and its residual may take just the matrix.
struct TermPoints {
  TermPoints() = default;
  TermPoints(Eigen::MatrixXd points) : x(std::move(points)) {}  // NOLINT: per-point terms
  operator const Eigen::MatrixXd&() const { return x; }        // NOLINT: per-point terms

  // Rows of the residual: one per group, or one per point.
  Eigen::Index residual_rows() const {
    return groups.empty() ? x.rows() : static_cast<Eigen::Index>(groups.size()) - 1;
  }

  Eigen::MatrixXd x;
  Eigen::MatrixXd tangents;  // empty: the spec's tangents for every point
  std::vector<Eigen::Index> groups;
  std::shared_ptr<const void> context;
};

// One term of the training loss: where its points come from, which streams it needs and
// how its residual reads them. A residual over groups (TermPoints.groups) writes one row of
// r per group of the block it is given (autodiff::groups_in_block) and is trained by Adam
// and L-BFGS; Levenberg–Marquardt takes per-point residuals only.
struct LossTerm {
  std::string name;       // shown in progress lines and metrics.json ("pde", "dirichlet", …)
  std::string batch_key;  // the training.batch entry giving its size: interior, boundary, …
                          // (empty: the term draws a fixed set of its own, measurements)
  double weight = 1.0;
  autodiff::StreamSpec spec;
  // Draws the points of a batch of `n` (points, or groups for a term over groups).
  std::function<TermPoints(Random&, Eigen::Index n)> sample;
  std::function<std::unique_ptr<Residual>(const TermPoints& points)> residual;
  // Optional: called when training stage s (0-based) starts, for terms whose residual
  // changes from stage to stage (a continuation parameter such as the eikonal viscosity);
  // residual() builds the current stage's residual afterwards. Before any call it builds the
  // last stage's, which the outputs after training use.
  std::function<void(int stage)> begin_stage;
};

// The gradient of a loss with respect to its residuals' extra parameters (unknown constants,
// Residual::extra_parameters), gathered from the blocks of one pass, which run on several
// threads, and summed in the order of the blocks: a run stays repeatable bit for bit for a
// given thread count, as the field's gradient is. A block may add more than once (a
// multiscale field's loss evaluates each scale's outputs of the block in turn, in one
// thread): its additions are summed in the order they come.
class ExtraGradient {
 public:
  void add(Eigen::Index first, Eigen::VectorXd g) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto [at, inserted] = blocks_.try_emplace(first, std::move(g));
    if (!inserted) at->second += g;
  }
  // Σ over the blocks added since the last clear (q entries).
  Eigen::VectorXd sum(Eigen::Index q) const {
    Eigen::VectorXd total = Eigen::VectorXd::Zero(q);
    for (const auto& [first, g] : blocks_) total += g;
    return total;
  }
  void clear() { blocks_.clear(); }

 private:
  std::mutex mutex_;
  std::map<Eigen::Index, Eigen::VectorXd> blocks_;
};

// Adapts a residual on a point set to the autodiff StreamLoss: w/N Σ ‖r‖², r̄ = 2w r / N,
// N the residual's rows (points, or groups).
// With per-point weights aₙ (one per point of the set; causal training weights time slices
// this way) the loss is w/N Σ aₙ ‖r(xₙ)‖² and r̄ₙ = 2w aₙ rₙ / N: the aₙ are constants of
// the pass, never differentiated.
// A pass over part of the set (one rank's share in data-parallel training) starts at row
// `offset` of it: the residual and the point weights are read there, N stays the whole set's.
// With `extra` (and a residual with extra parameters), each block also adds its
// Σ r̄ · ∂r/∂c there.
template <typename Scalar>
class ResidualLoss final : public autodiff::StreamLoss<Scalar> {
 public:
  ResidualLoss(const Residual& residual, double weight, Eigen::Index total_points,
               const Eigen::VectorXd* point_weights = nullptr, Eigen::Index offset = 0,
               ExtraGradient* extra = nullptr)
      : residual_(residual), scale_(weight / static_cast<double>(total_points)),
        point_weights_(point_weights), offset_(offset), extra_(extra) {}
  double evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                  Streams<Scalar>& adjoint) const override {
    return evaluate_with(residual_, first, layout, out, adjoint);
  }
  double evaluate_scale(int scale, Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                        Streams<Scalar>& adjoint) const override {
    return evaluate_with(residual_.at_scale(scale), first, layout, out, adjoint);
  }

 private:
  double evaluate_with(const Residual& residual, Eigen::Index first, const StreamLayout& layout,
                       const Streams<Scalar>& out, Streams<Scalar>& adjoint) const;

  const Residual& residual_;
  double scale_;
  const Eigen::VectorXd* point_weights_;  // not owned; null: all 1
  Eigen::Index offset_;
  ExtraGradient* extra_;  // not owned; null: not gathered
};

// Adapts a residual on a point set to autodiff::StreamResidual, scaled by √(w/N): the
// least-squares form of a loss term, whose squares sum to the term's loss w/N Σ‖r‖²
// (for Levenberg–Marquardt, which wants residuals and their Jacobian rather than a loss).
// `offset` as in ResidualLoss.
template <typename Scalar>
class ScaledResidual final : public autodiff::StreamResidual<Scalar> {
 public:
  ScaledResidual(const Residual& residual, double weight, Eigen::Index total_points,
                 Eigen::Index offset = 0);
  int components() const override { return residual_.components(); }
  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                autodiff::Matrix<Scalar>& r) const override;
  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                const autodiff::Matrix<Scalar>& r_bar, Streams<Scalar>& adjoint) const override;
  int extra_parameters() const override { return residual_.extra_parameters(); }
  void extra_jacobian(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                      autodiff::Matrix<Scalar>& jacobian) const override;

 private:
  const Residual& residual_;
  double scale_;
  Eigen::Index offset_;
};

}  // namespace nfield::solvers
