// SPDX-License-Identifier: MIT
#include "solvers/training/adaptive_refinement.h"

#include <stdexcept>

namespace nfield::solvers {

template <typename Scalar>
AdaptiveRefinement<Scalar>::AdaptiveRefinement(const AdaptiveOptions& options, std::size_t term,
                                               std::string term_name)
    : options_(options), term_(term), term_name_(std::move(term_name)) {}

template <typename Scalar>
bool AdaptiveRefinement<Scalar>::before_step(StrategyView<Scalar>& view) {
  if (view.step() == 0 || view.step() % options_.every != 0) return false;
  refine(view);
  return true;
}

template <typename Scalar>
void AdaptiveRefinement<Scalar>::points_drawn(std::size_t k, TermPoints& points) {
  if (k != term_) return;
  joined_rows_ = points_.rows();
  if (points_.rows() == 0) return;
  if (!points.groups.empty() || points.tangents.size() > 0)
    throw std::logic_error("training.adaptive: loss term '" + term_name_ +
                           "' reads groups of points or per-point tangents; refinement adds "
                           "single points");
  Eigen::MatrixXd joined(points.x.rows() + points_.rows(), points.x.cols());
  joined << points.x, points_;
  points.x = std::move(joined);
}

template <typename Scalar>
void AdaptiveRefinement<Scalar>::between_segments(StrategyView<Scalar>& view, bool redraw) {
  refine(view);
  if (redraw) return;  // the new points get the set in points_drawn
  // The stage's own points stay; only the set behind them changes.
  const Eigen::MatrixXd& x = view.points(term_).x;
  const Eigen::Index own = x.rows() - joined_rows_;
  Eigen::MatrixXd joined(own + points_.rows(), x.cols());
  joined << x.topRows(own), points_;
  view.replace_points(term_, std::move(joined));
  joined_rows_ = points_.rows();
}

template <typename Scalar>
void AdaptiveRefinement<Scalar>::refine(StrategyView<Scalar>& view) {
  const TermPoints candidates = view.sample(term_, options_.candidates);
  const std::vector<Eigen::Index> best =
      largest(view.squared_residuals(term_, candidates), options_.add);
  append_capped(points_, candidates.x(best, Eigen::all), options_.max_points);
}

template <typename Scalar>
void AdaptiveRefinement<Scalar>::metrics(std::vector<std::pair<std::string, double>>& out) const {
  out.emplace_back("adaptive_points", static_cast<double>(points_.rows()));
}

template <typename Scalar>
void AdaptiveRefinement<Scalar>::save(io::H5Writer& file, const std::string& group) const {
  if (points_.rows() > 0) file.write(group + "/adaptive_points", points_);
}

template <typename Scalar>
void AdaptiveRefinement<Scalar>::load(const io::H5Reader& file, const std::string& group) {
  points_.resize(0, 0);
  if (file.has_dataset(group + "/adaptive_points"))
    points_ = file.read_matrix<double>(group + "/adaptive_points");
}

template class AdaptiveRefinement<float>;
template class AdaptiveRefinement<double>;

}  // namespace nfield::solvers
