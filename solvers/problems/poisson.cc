// SPDX-License-Identifier: MIT
//
// Poisson: Δu = f in a box of 1–3 dimensions, with Dirichlet and Neumann conditions.
//
//   problem: poisson
//   equation:
//     source: "-2*pi^2*sin(pi*x)*sin(pi*y)"   # f
//     exact: "sin(pi*x)*sin(pi*y)"            # optional: error metrics
//     focus:                                  # optional: more interior points in regions
//       - {where: "x^2 + y^2 < 0.04", batch: corner, weight: 1}
//
// Focus. Each item adds a term pde_BATCH: the same residual at `training.batch.BATCH` points
// uniform over the part of Ω where `where` is nonzero (Domain::sample_interior_where), so the
// points are graded: denser there by (its points / its area) against the interior's. For a
// singularity (a re-entrant corner, where ∇u ~ r^{−1/3}) nested regions give a grading
// towards it. The equation is the user's: only where its residual is sampled changes. A
// region no point of 2¹⁴ drawn in the domain lies in is refused at load (located, `where`).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

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
    if (equation.has("focus")) read_focus(equation.child("focus"));
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
    for (const Focus& f : focus_) {
      LossTerm term = pde;
      term.name = "pde_" + f.batch;
      term.batch_key = f.batch;
      term.weight = f.weight;
      term.sample = [this, where = f.where](Random& rng, Eigen::Index n) {
        return domain_.sample_interior_where(rng, n, *where);
      };
      terms.push_back(std::move(term));
    }
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    return terms;
  }

  std::shared_ptr<const Ansatz> ansatz() const override { return ansatz_; }
  bool has_exact() const override { return exact_ != nullptr; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override { return exact_->evaluate(x); }

 private:
  struct Focus {
    std::string batch;
    double weight = 1;
    std::shared_ptr<const io::Expression> where;
  };

  void read_focus(const io::ConfigNode& list) {
    if (!list.is_sequence() || list.size() == 0)
      throw list.error("expected a non-empty list of {where: EXPR, batch: NAME, weight: w}");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const io::ConfigNode item = list.at(i);
      Focus f;
      f.where = read_interior_region(item, "where", domain_);
      f.weight = item.get_or("weight", 1.0);
      item.require("weight", std::isfinite(f.weight) && f.weight >= 0, "expected a weight >= 0");
      f.batch = item.get_or("batch", i == 0 ? std::string("focus") : "focus_" + std::to_string(i));
      item.require("batch", !f.batch.empty() && std::all_of(f.batch.begin(), f.batch.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
      }), "expected a training.batch key (letters, digits, '_')");
      const bool taken = f.batch == "interior" || std::any_of(focus_.begin(), focus_.end(), [&](const Focus& o) {
        return o.batch == f.batch;
      });
      item.require("batch", !taken, "batch '" + f.batch + "' is taken (interior, or another focus item)");
      item.reject_unknown_keys();
      focus_.push_back(std::move(f));
    }
  }

  Domain domain_;
  std::vector<Focus> focus_;
  std::shared_ptr<io::Expression> source_, exact_;
  std::vector<LossTerm> conditions_;
  std::shared_ptr<const Ansatz> ansatz_;
};

}  // namespace

std::unique_ptr<Problem> make_poisson(const ProblemContext& context) {
  return std::make_unique<Poisson>(context);
}

}  // namespace nfield::solvers
