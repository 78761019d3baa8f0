// SPDX-License-Identifier: MIT
#include "solvers/conditions/conditions.h"

#include "io/text.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/conditions/hard_constraints.h"

namespace nfield::solvers {

namespace {

LinearResidual value_residual(const Eigen::MatrixXd& target) {
  std::vector<LinearResidual::Term> terms;
  for (Eigen::Index c = 0; c < target.cols(); ++c)
    terms.push_back({static_cast<int>(c), 0, static_cast<int>(c), Eigen::VectorXd::Ones(1)});
  return LinearResidual(std::move(terms), target);
}

}  // namespace

std::vector<LossTerm> condition_terms(const io::ConfigNode& conditions, const Domain& domain,
                                      int output_dim, std::shared_ptr<const Ansatz>* ansatz,
                                      const io::ExpressionConstants& constants) {
  std::vector<LossTerm> terms;
  if (conditions.is_null()) return terms;
  conditions.require(conditions.is_sequence(), "expected a list of conditions");
  if (ansatz) *ansatz = read_ansatz(conditions, domain, output_dim, constants);
  for (std::size_t i = 0; i < conditions.size(); ++i) {
    const io::ConfigNode item = conditions.at(i);
    if (item.get_choice("enforce", {"soft", "hard"}, "soft") == "hard") {
      if (!ansatz)
        throw item.error("enforce", "this problem does not support enforce: hard (poisson, pde and "
                                    "wave do); use enforce: soft");
      item.reject_unknown_keys();
      continue;  // enforced by the ansatz, no loss term
    }
    const bool initial = item.has("on") && !item.has_list("on") &&
                         io::to_lower(item.get<std::string>("on")) == "initial";
    LossTerm term;
    term.weight = item.get_or("weight", 1.0);
    item.require("weight", term.weight >= 0, "expected a weight >= 0");
    const auto values = channel_expressions(item, "value", domain, output_dim, constants);
    if (initial) {
      if (!domain.has_time()) throw item.error("on", "'initial' needs a domain with a time interval");
      const std::string type = item.get_choice("type", {"value", "velocity"});
      term.batch_key = "initial";
      term.sample = [&domain](Random& rng, Eigen::Index n) { return domain.sample_initial(rng, n); };
      if (type == "value") {
        term.name = "initial";
        term.spec = autodiff::StreamSpec::values(domain.input_dim());
        term.residual = [values](const Eigen::MatrixXd& x) {
          return std::make_unique<LinearResidual>(value_residual(evaluate_channels(values, x)));
        };
      } else {
        term.name = "initial_velocity";
        term.spec = autodiff::StreamSpec::values(domain.input_dim());
        term.spec.tangents = Eigen::MatrixXd::Zero(domain.input_dim(), 1);
        term.spec.tangents(domain.time_column(), 0) = 1.0;
        term.residual = [values](const Eigen::MatrixXd& x) {
          const Eigen::MatrixXd target = evaluate_channels(values, x);
          std::vector<LinearResidual::Term> t;
          for (Eigen::Index c = 0; c < target.cols(); ++c)
            t.push_back({static_cast<int>(c), 1, static_cast<int>(c), Eigen::VectorXd::Ones(1)});
          return std::make_unique<LinearResidual>(std::move(t), target);
        };
      }
    } else {
      const std::string type = item.get_choice("type", {"dirichlet", "neumann"});
      const std::vector<Face> faces = condition_faces(item, domain);
      term.batch_key = "boundary";
      term.sample = [&domain, faces](Random& rng, Eigen::Index n) {
        return domain.sample_faces(faces, rng, n);
      };
      if (type == "dirichlet") {
        term.name = "dirichlet";
        term.spec = autodiff::StreamSpec::values(domain.input_dim());
        term.residual = [values](const Eigen::MatrixXd& x) {
          return std::make_unique<LinearResidual>(value_residual(evaluate_channels(values, x)));
        };
      } else {
        term.name = "neumann";
        term.spec = autodiff::StreamSpec::gradient(domain.input_dim());
        const Domain* d = &domain;
        term.residual = [values, faces, d](const Eigen::MatrixXd& x) {
          const Eigen::MatrixXd target = evaluate_channels(values, x);
          // Each point's outward normal, from the face coordinate it was put on.
          Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(x.rows(), d->space_dim());
          for (Eigen::Index r = 0; r < x.rows(); ++r)
            for (const Face& f : faces)
              if (x(r, f.axis) == (f.upper ? d->upper()[f.axis] : d->lower()[f.axis])) {
                normal(r, f.axis) = f.upper ? 1.0 : -1.0;
                break;
              }
          std::vector<LinearResidual::Term> t;
          for (Eigen::Index c = 0; c < target.cols(); ++c)
            for (int a = 0; a < d->space_dim(); ++a)
              t.push_back({static_cast<int>(c), 1 + a, static_cast<int>(c), normal.col(a)});
          return std::make_unique<LinearResidual>(std::move(t), target);
        };
      }
    }
    if (!term.name.empty()) term.name += i > 0 ? "_" + std::to_string(i) : "";
    item.reject_unknown_keys();
    terms.push_back(std::move(term));
  }
  return terms;
}

}  // namespace nfield::solvers
