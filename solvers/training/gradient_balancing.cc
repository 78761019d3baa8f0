// SPDX-License-Identifier: MIT
#include "solvers/training/gradient_balancing.h"

#include "solvers/core/problem.h"
#include "solvers/training/communicator.h"
#include "solvers/training/strategy_settings.h"

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

namespace {

class BalanceSettings final : public StrategySettingsOf<BalanceSettings, BalanceOptions> {
 public:
  void read(const io::ConfigNode& training) override {
    if (!training.has("balance")) return;
    if (training.has_map("balance")) {
      const io::ConfigNode b = training.child("balance");
      options.method = b.get_choice("method", {"fixed", "grad_norm"});
      if (b.has("every")) options.every = b.get_in_range("every", 1, 1 << 30);
      if (b.has("alpha")) options.alpha = b.get_in_range("alpha", 0.0, 1.0);
      b.require("alpha", options.alpha > 0, "expected alpha in (0, 1]");
      b.reject_unknown_keys();
    } else {
      options.method = training.get_choice("balance", {"fixed", "grad_norm"});
    }
  }
  void write(YAML::Node& n) const override {
    if (options.method == "fixed") {
      n["balance"] = options.method;
      return;
    }
    n["balance"]["method"] = options.method;
    n["balance"]["every"] = options.every;
    n["balance"]["alpha"] = io::yaml_number(options.alpha);
  }
  bool enabled() const override { return options.method != "fixed"; }
  void check(const io::ConfigNode& training, const Problem& problem) const override {
    require_residual_term(training, "balance", problem);
  }
  template <typename Scalar>
  static std::unique_ptr<TrainingStrategy<Scalar>> make(const BalanceOptions& o, const Problem& problem,
                                                        const std::vector<std::string>& names) {
    return std::make_unique<GradientBalancing<Scalar>>(o, residual_term_for("balance", problem, names), names);
  }
};

}  // namespace

std::unique_ptr<StrategySettings> make_balance_settings() { return std::make_unique<BalanceSettings>(); }

}  // namespace nfield::solvers
