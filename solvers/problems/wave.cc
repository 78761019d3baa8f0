// SPDX-License-Identifier: MIT
//
// Wave equation: u_tt = c²Δu + f on a box of 1–3 space dimensions times a time interval
// [t0, t1] (field inputs x…, t), with initial displacement and velocity from the
// `initial` conditions and Dirichlet/Neumann conditions on the space faces.
//
//   problem: wave
//   domain: {lower: [0], upper: [1], time: [0, 1]}
//   equation:
//     speed: 2                    # c: a number, or an expression c(x, y, z, t) > 0
//     source: "0"                 # f, optional (default 0)
//     exact: "sin(pi*x)*cos(2*pi*t)"   # optional: error metrics
//   conditions:
//     - {on: boundary, type: dirichlet, value: "0"}
//     - {on: initial, type: value, value: "sin(pi*x)", weight: 10}
//     - {on: initial, type: velocity, value: "0", weight: 10}
//
// The interior residual is r = u_tt − c²Δu − f (loss term "pde"). With `enforce: hard` on
// the Dirichlet and initial items, u = u0 + τ v0 + φ(x) ψ(τ)² N satisfies them exactly and
// "pde" is the only loss term (solvers/conditions/hard_constraints.h).
//
// How the second derivatives travel: a constant speed makes the wave operator one operator
// stream tr(C ∇²u) with C = diag(−c², …, −c², 1) over the axes (x…, t), so a 1D + time
// field costs 1 + 2 + 1 = 4 streams. A speed that varies in space or time cannot ride in C
// (C is the same for every point of a pass), so then the pass carries two operator streams,
// u_tt (C = e_t e_tᵀ) and Δu (C = diag(1, …, 1, 0)), and the residual weights the second by
// the per-point coefficient −c(x)² — one stream more, same residual.
#include <cmath>

#include "solvers/conditions/conditions.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

class Wave final : public Problem {
 public:
  explicit Wave(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {
    if (!domain_.has_time())
      throw context.root.child("domain").error(
          "time", "the wave equation needs a time interval (domain.time: [t0, t1])");
    const io::ConfigNode equation = context.root.child("equation");
    const auto vars = domain_.expression_variables();
    const io::Expression speed = equation.get_expression("speed", vars);
    if (speed.is_constant()) {
      const double point[1] = {0.0};
      const double c = speed.evaluate(std::span<const double>(point, 0));
      equation.require("speed", std::isfinite(c) && c > 0, "expected a speed c > 0");
      constant_speed_ = c;
    } else {
      speed_ = std::make_shared<io::Expression>(speed);
    }
    source_ = std::make_shared<io::Expression>(equation.get_expression_or("source", "0", vars));
    if (equation.has("exact"))
      exact_ = std::make_shared<io::Expression>(equation.get_expression("exact", vars));
    equation.reject_unknown_keys();
    // (condition_terms rejects the empty mapping child_or_empty gives for an absent key.)
    if (context.root.has("conditions"))
      conditions_ = condition_terms(context.root.child("conditions"), domain_, 1, &ansatz_);
  }

  const Domain& domain() const override { return domain_; }

  std::vector<LossTerm> loss_terms() const override {
    const int d = domain_.space_dim(), n_in = domain_.input_dim(), t = domain_.time_column();
    LossTerm pde;
    pde.name = "pde";
    pde.batch_key = "interior";
    pde.spec = autodiff::StreamSpec::gradient(n_in);
    pde.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    const auto source = source_;
    if (!speed_) {
      // One stream: tr(C ∇²u) = u_tt − c²Δu.
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n_in, n_in);
      for (int a = 0; a < d; ++a) c(a, a) = -constant_speed_ * constant_speed_;
      c(t, t) = 1.0;
      const int q = pde.spec.add_operator(c);
      const int stream = autodiff::StreamLayout(pde.spec).op(q);
      pde.residual = [source, stream](const Eigen::MatrixXd& x) {
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, stream, 0, Eigen::VectorXd::Ones(1)}},
            Eigen::MatrixXd(source->evaluate(x)));
      };
    } else {
      // Two streams, u_tt and Δu, the second weighted by −c(x)² per point.
      Eigen::MatrixXd tt = Eigen::MatrixXd::Zero(n_in, n_in), lap = Eigen::MatrixXd::Zero(n_in, n_in);
      tt(t, t) = 1.0;
      for (int a = 0; a < d; ++a) lap(a, a) = 1.0;
      const int q_tt = pde.spec.add_operator(tt);
      const int q_lap = pde.spec.add_operator(lap);
      const autodiff::StreamLayout layout(pde.spec);
      const int s_tt = layout.op(q_tt), s_lap = layout.op(q_lap);
      const auto speed = speed_;
      pde.residual = [source, speed, s_tt, s_lap](const Eigen::MatrixXd& x) {
        const Eigen::VectorXd c = speed->evaluate(x);
        const Eigen::VectorXd minus_c2 = -c.array().square().matrix();
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, s_tt, 0, Eigen::VectorXd::Ones(1)},
                                              {0, s_lap, 0, minus_c2}},
            Eigen::MatrixXd(source->evaluate(x)));
      };
    }
    std::vector<LossTerm> terms{pde};
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    return terms;
  }

  std::shared_ptr<const Ansatz> ansatz() const override { return ansatz_; }
  bool has_exact() const override { return exact_ != nullptr; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override { return exact_->evaluate(x); }

 private:
  Domain domain_;
  double constant_speed_ = 0;                     // when the speed is a number
  std::shared_ptr<io::Expression> speed_;         // when it varies (else null)
  std::shared_ptr<io::Expression> source_, exact_;
  std::vector<LossTerm> conditions_;
  std::shared_ptr<const Ansatz> ansatz_;
};

}  // namespace

std::unique_ptr<Problem> make_wave(const ProblemContext& context) {
  return std::make_unique<Wave>(context);
}

}  // namespace nfield::solvers
