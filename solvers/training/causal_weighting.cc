// SPDX-License-Identifier: MIT
#include "solvers/training/causal_weighting.h"

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

}  // namespace nfield::solvers
