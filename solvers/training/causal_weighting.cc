// SPDX-License-Identifier: MIT
#include "solvers/training/causal_weighting.h"

#include <stdexcept>

#include "solvers/core/problem.h"
#include "solvers/training/strategy_settings.h"

namespace nfield::solvers {

template <typename Scalar>
CausalWeighting<Scalar>::CausalWeighting(const CausalOptions& options, std::size_t term,
                                         int time_column, double t0, double t1)
    : options_(options), term_(term), time_column_(time_column), t0_(t0), t1_(t1) {}

template <typename Scalar>
int CausalWeighting<Scalar>::segment_limit(bool reweighted) const {
  return reweighted ? options_.every : TrainingStrategy<Scalar>::segment_limit(reweighted);
}

template <typename Scalar>
void CausalWeighting<Scalar>::update_weights(StrategyView<Scalar>& view) {
  const Eigen::VectorXd r2 = view.squared_residuals(term_);
  weights_ = causal_weights(view.points(term_).x.col(time_column_), r2, t0_, t1_,
                            options_.slices, options_.epsilon);
}

template <typename Scalar>
const Eigen::VectorXd* CausalWeighting<Scalar>::point_weights(std::size_t k,
                                                              const TermPoints& points) const {
  return k == term_ && weights_.point_weights.size() == points.x.rows() ? &weights_.point_weights
                                                                        : nullptr;
}

template <typename Scalar>
void CausalWeighting<Scalar>::metrics(std::vector<std::pair<std::string, double>>& out) const {
  if (!weights_.weights.empty()) out.emplace_back("causal_min_weight", weights_.min_weight());
}

template <typename Scalar>
void CausalWeighting<Scalar>::progress(std::vector<std::pair<std::string, double>>& out) const {
  if (!weights_.weights.empty()) out.emplace_back("causal min w", weights_.min_weight());
}

template <typename Scalar>
void CausalWeighting<Scalar>::save(io::H5Writer& file, const std::string& group) const {
  if (!weights_.weights.empty()) file.write(group + "/causal_weights", weights_.weights);
}

template <typename Scalar>
void CausalWeighting<Scalar>::load(const io::H5Reader& file, const std::string& group) {
  if (!file.has_dataset(group + "/causal_weights")) return;
  const Eigen::VectorXd c = file.read_vector<double>(group + "/causal_weights");
  weights_.weights.assign(c.data(), c.data() + c.size());
}

template class CausalWeighting<float>;
template class CausalWeighting<double>;

namespace {

class CausalSettings final : public StrategySettingsOf<CausalSettings, CausalOptions> {
 public:
  void read(const io::ConfigNode& training) override {
    if (!training.has("causal")) return;
    const io::ConfigNode c = training.child("causal");
    c.require(c.is_map(), "expected a mapping such as {epsilon: 1.0, slices: 32}");
    options.enabled = true;
    if (c.has("epsilon")) options.epsilon = c.get_in_range("epsilon", 0.0, 1e12);
    if (c.has("slices")) options.slices = c.get_in_range("slices", 1, 1 << 16);
    if (c.has("every")) options.every = c.get_in_range("every", 1, 1 << 30);
    c.reject_unknown_keys();
  }
  void write(YAML::Node& n) const override {
    if (!options.enabled) return;
    n["causal"]["epsilon"] = io::yaml_number(options.epsilon);
    n["causal"]["slices"] = options.slices;
    n["causal"]["every"] = options.every;
  }
  bool enabled() const override { return options.enabled; }
  void check(const io::ConfigNode& training, const Problem& problem) const override {
    require_residual_term(training, "causal", problem);
    if (!problem.domain().has_time())
      throw training.error("causal", "causal weighting needs a time axis (domain.time: [t0, t1])");
  }
  template <typename Scalar>
  static std::unique_ptr<TrainingStrategy<Scalar>> make(const CausalOptions& o, const Problem& problem,
                                                        const std::vector<std::string>& names) {
    const std::size_t term = residual_term_for("causal", problem, names);
    const Domain& domain = problem.domain();
    if (!domain.has_time()) throw std::invalid_argument("training.causal needs a time axis (domain.time)");
    const auto [t0, t1] = domain.time();
    return std::make_unique<CausalWeighting<Scalar>>(o, term, domain.time_column(), t0, t1);
  }
};

}  // namespace

std::unique_ptr<StrategySettings> make_causal_settings() { return std::make_unique<CausalSettings>(); }

}  // namespace nfield::solvers
