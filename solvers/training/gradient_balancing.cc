// SPDX-License-Identifier: MIT
#include "solvers/training/gradient_balancing.h"

#include "solvers/training/communicator.h"

namespace nfield::solvers {

template <typename Scalar>
GradientBalancing<Scalar>::GradientBalancing(const BalanceOptions& options, std::size_t term,
                                             std::vector<std::string> term_names)
    : options_(options), term_(term), names_(std::move(term_names)),
      lambda_(names_.size(), 1.0) {}

template <typename Scalar>
bool GradientBalancing<Scalar>::step_gradient(StrategyView<Scalar>& view, Scalar* gradient) {
  if (view.step() % options_.every != 0) return false;
  const Eigen::Index n = view.parameter_count();
  const std::size_t terms = lambda_.size();
  Communicator& communicator = view.communicator();
  const bool parallel = communicator.size() > 1;
  std::vector<autodiff::Vector<Scalar>> g(terms);
  std::vector<double> losses(terms);
  for (std::size_t k = 0; k < terms; ++k) {
    g[k] = autodiff::Vector<Scalar>::Zero(n);
    losses[k] = view.term_loss(k, view.term_weight(k), g[k].data());
    if (parallel) communicator.allreduce_sum(g[k].data(), static_cast<std::size_t>(n));
  }
  if (parallel) communicator.allreduce_sum(losses.data(), losses.size());
  const Eigen::VectorXd reference = g[term_].template cast<double>();
  const double alpha = options_.alpha;
  Eigen::Map<autodiff::Vector<Scalar>> sum(gradient, n);
  sum.setZero();
  for (std::size_t k = 0; k < terms; ++k) {
    if (k != term_) {
      const double target = grad_norm_target(reference, g[k].template cast<double>(),
                                             view.term_weight(k), lambda_[k]);
      lambda_[k] = (1 - alpha) * lambda_[k] + alpha * target;
    }
    sum += static_cast<Scalar>(lambda_[k]) * g[k];
    view.set_term_loss(k, losses[k] * lambda_[k]);
  }
  return true;
}

template <typename Scalar>
void GradientBalancing<Scalar>::metrics(std::vector<std::pair<std::string, double>>& out) const {
  for (std::size_t k = 0; k < names_.size(); ++k)
    out.emplace_back("balance_weight_" + names_[k], lambda_[k]);
}

template <typename Scalar>
void GradientBalancing<Scalar>::save(io::H5Writer& file, const std::string& group) const {
  file.write(group + "/balance_weights", lambda_);
}

template <typename Scalar>
void GradientBalancing<Scalar>::load(const io::H5Reader& file, const std::string& group) {
  if (!file.has_dataset(group + "/balance_weights")) return;
  const Eigen::VectorXd b = file.read_vector<double>(group + "/balance_weights");
  if (b.size() == static_cast<Eigen::Index>(lambda_.size())) lambda_.assign(b.data(), b.data() + b.size());
}

template class GradientBalancing<float>;
template class GradientBalancing<double>;

}  // namespace nfield::solvers
