// SPDX-License-Identifier: MIT
#include "solvers/conditions/conditions.h"

#include "solvers/conditions/condition_values.h"
#include "solvers/conditions/periodic.h"

namespace nfield::solvers {

namespace {

// The constrained outputs' values at x (n × item.outputs.size()).
Eigen::MatrixXd targets(const ConditionItem& item, const Eigen::MatrixXd& x) {
  Eigen::MatrixXd g(x.rows(), static_cast<Eigen::Index>(item.outputs.size()));
  for (size_t k = 0; k < item.outputs.size(); ++k)
    g.col(static_cast<Eigen::Index>(k)) = item.values[static_cast<size_t>(item.outputs[k])]->evaluate(x);
  return g;
}

// Component k reads output item.outputs[k] from `stream`.
LinearResidual value_residual(const ConditionItem& item, const Eigen::MatrixXd& x, int stream) {
  std::vector<LinearResidual::Term> terms;
  for (size_t k = 0; k < item.outputs.size(); ++k)
    terms.push_back({static_cast<int>(k), stream, item.outputs[k], Eigen::VectorXd::Ones(1)});
  return LinearResidual(std::move(terms), targets(item, x));
}

// Each point's outward normal (n × space_dim), from the face coordinate it was put on.
Eigen::MatrixXd outward_normals(const Domain& d, const std::vector<Face>& faces, const Eigen::MatrixXd& x) {
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(x.rows(), d.space_dim());
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    for (const Face& f : faces)
      if (x(r, f.axis) == (f.upper ? d.upper()[f.axis] : d.lower()[f.axis])) {
        normal(r, f.axis) = f.upper ? 1.0 : -1.0;
        break;
      }
  return normal;
}

// a u + b ∂u/∂n − g (neumann: a absent, b = 1), from the value and the gradient streams of
// `layout` (tangents along the axes).
std::unique_ptr<Residual> normal_residual(const ConditionItem& item, const Domain& d,
                                          const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) {
  const Eigen::MatrixXd normal =
      item.parts ? Eigen::MatrixXd(d.boundary_normals(x).leftCols(d.space_dim())) : outward_normals(d, item.faces, x);
  const Eigen::VectorXd b = item.robin_b ? item.robin_b->evaluate(x) : Eigen::VectorXd::Ones(x.rows());
  std::vector<LinearResidual::Term> t;
  for (size_t k = 0; k < item.outputs.size(); ++k) {
    const int c = item.outputs[k], component = static_cast<int>(k);
    if (item.robin_a) t.push_back({component, layout.value(), c, item.robin_a->evaluate(x)});
    for (int a = 0; a < d.space_dim(); ++a)
      t.push_back({component, layout.tangent(a), c, item.robin_b ? Eigen::VectorXd(normal.col(a).cwiseProduct(b))
                                                     : Eigen::VectorXd(normal.col(a))});
  }
  return std::make_unique<LinearResidual>(std::move(t), targets(item, x));
}

LossTerm term_of(const ConditionItem& item, const Domain& domain) {
  LossTerm term;
  term.weight = item.weight;
  const auto shared = std::make_shared<const ConditionItem>(item);
  if (item.initial) {
    term.batch_key = "initial";
    term.sample = [&domain](Random& rng, Eigen::Index n) { return domain.sample_initial(rng, n); };
    term.spec = autodiff::StreamSpec::values(domain.input_dim());
    int stream = autodiff::StreamLayout::value();
    term.name = "initial";
    if (item.type == ConditionType::kInitialVelocity) {
      term.name = "initial_velocity";
      term.spec.tangents = Eigen::MatrixXd::Zero(domain.input_dim(), 1);
      term.spec.tangents(domain.time_column(), 0) = 1.0;
      stream = autodiff::StreamLayout(term.spec).tangent(0);
    }
    term.residual = [shared, stream](const Eigen::MatrixXd& x) {
      return std::make_unique<LinearResidual>(value_residual(*shared, x, stream));
    };
    return term;
  }
  term.batch_key = "boundary";
  if (item.parts)
    term.sample = [&domain, parts = *item.parts](Random& rng, Eigen::Index n) {
      return domain.sample_boundary(parts, rng, n).points;
    };
  else
    term.sample = [&domain, faces = item.faces](Random& rng, Eigen::Index n) {
      return domain.sample_faces(faces, rng, n);
    };
  switch (item.type) {
    case ConditionType::kDirichlet:
      term.name = "dirichlet";
      term.spec = autodiff::StreamSpec::values(domain.input_dim());
      term.residual = [shared](const Eigen::MatrixXd& x) {
        return std::make_unique<LinearResidual>(value_residual(*shared, x, autodiff::StreamLayout::value()));
      };
      break;
    case ConditionType::kNeumann:
    case ConditionType::kRobin:
      term.name = item.type == ConditionType::kNeumann ? "neumann" : "robin";
      term.spec = autodiff::StreamSpec::gradient(domain.input_dim());
      term.residual = [shared, d = &domain, layout = autodiff::StreamLayout(term.spec)](const Eigen::MatrixXd& x) {
        return normal_residual(*shared, *d, layout, x);
      };
      break;
    case ConditionType::kPeriodic:
      term.name = "periodic";
      term.spec = periodic_spec(domain, item.faces[0].axis);
      term.sample = [&domain, face = item.faces[0]](Random& rng, Eigen::Index n) {
        return periodic_points(domain, face, rng, n);
      };
      term.residual = [outputs = item.outputs](const TermPoints& points) {
        return std::make_unique<PeriodicResidual>(points.groups, outputs);
      };
      break;
    default:
      break;
  }
  return term;
}

}  // namespace

std::vector<LossTerm> condition_terms(const std::vector<ConditionItem>& items, const Domain& domain) {
  std::vector<LossTerm> terms;
  for (const ConditionItem& item : items) {
    if (item.hard || item.type == ConditionType::kResidual) continue;
    LossTerm term = term_of(item, domain);
    if (item.index > 0) term.name += "_" + std::to_string(item.index);
    terms.push_back(std::move(term));
  }
  return terms;
}

}  // namespace nfield::solvers
