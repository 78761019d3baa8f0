// SPDX-License-Identifier: MIT
//
// Poisson: Δu = f in a box of 1–3 dimensions, with Dirichlet and Neumann conditions.
//
//   problem: poisson
//   equation:
//     source: "-2*pi^2*sin(pi*x)*sin(pi*y)"   # f
//     exact: "sin(pi*x)*sin(pi*y)"            # optional: error metrics
#include "solvers/conditions/conditions.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

class Poisson final : public Problem {
 public:
  explicit Poisson(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"), context.config_dir)) {
    const io::ConfigNode equation = context.root.child("equation");
    const auto vars = domain_.expression_variables();
    source_ = std::make_shared<io::Expression>(equation.get_expression("source", vars));
    if (equation.has("exact")) exact_ = std::make_shared<io::Expression>(equation.get_expression("exact", vars));
    equation.reject_unknown_keys();
    ConditionReading reading;
    reading.allow_hard = true;
    const std::vector<ConditionItem> items = read_conditions(context.root.child_or_empty("conditions"), domain_, reading);
    ansatz_ = read_ansatz(items, domain_, 1);
    conditions_ = condition_terms(items, domain_);
  }

  const Domain& domain() const override { return domain_; }

  fields::SineFrequencies default_sine_frequencies() const override {
    return fields::kPdeSineFrequencies;  // a differential equation: fields/field_config.h
  }
  std::vector<LossTerm> loss_terms() const override {
    LossTerm pde;
    pde.name = "pde";
    pde.batch_key = "interior";
    const int d = domain_.space_dim();
    pde.spec = autodiff::StreamSpec::laplacian(d);
    pde.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    const auto source = source_;
    const int laplacian_stream = autodiff::StreamLayout(pde.spec).op(0);
    pde.residual = [source, laplacian_stream](const Eigen::MatrixXd& x) {
      Eigen::MatrixXd f = source->evaluate(x);
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{{0, laplacian_stream, 0, Eigen::VectorXd::Ones(1)}}, f);
    };
    std::vector<LossTerm> terms{pde};
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    return terms;
  }

  std::shared_ptr<const Ansatz> ansatz() const override { return ansatz_; }
  bool has_exact() const override { return exact_ != nullptr; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override { return exact_->evaluate(x); }

 private:
  Domain domain_;
  std::shared_ptr<io::Expression> source_, exact_;
  std::vector<LossTerm> conditions_;
  std::shared_ptr<const Ansatz> ansatz_;
};

}  // namespace

std::unique_ptr<Problem> make_poisson(const ProblemContext& context) {
  return std::make_unique<Poisson>(context);
}

}  // namespace nfield::solvers
