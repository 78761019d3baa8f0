// SPDX-License-Identifier: MIT
#include "solvers/training/adaptive_refinement.h"

#include <algorithm>
#include <stdexcept>

#include "solvers/core/problem.h"
#include "solvers/training/strategy_settings.h"

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

namespace {

class AdaptiveSettings final : public StrategySettingsOf<AdaptiveSettings, AdaptiveOptions> {
 public:
  void read(const io::ConfigNode& training) override {
    if (!training.has("adaptive")) return;
    AdaptiveOptions& o = options;
    const io::ConfigNode a = training.child("adaptive");
    a.require(a.is_map(), "expected a mapping such as {every: 500, candidates: 10000, add: 100}");
    o.enabled = true;
    if (a.has("every")) o.every = a.get_in_range("every", 1, 1 << 30);
    if (a.has("candidates")) o.candidates = a.get_in_range<long>("candidates", 1, 1L << 24);
    if (a.has("add")) o.add = a.get_in_range<long>("add", 1, o.candidates);
    a.require("add", o.add <= o.candidates, "expected add <= candidates");
    o.max_points = a.has("max_points") ? a.get_in_range<long>("max_points", o.add, 1L << 26)
                                       : std::max(o.max_points, o.add);
    a.reject_unknown_keys();
  }
  void write(YAML::Node& n) const override {
    if (!options.enabled) return;
    n["adaptive"]["every"] = options.every;
    n["adaptive"]["candidates"] = options.candidates;
    n["adaptive"]["add"] = options.add;
    n["adaptive"]["max_points"] = options.max_points;
  }
  bool enabled() const override { return options.enabled; }
  void check(const io::ConfigNode& training, const Problem& problem) const override {
    require_residual_term(training, "adaptive", problem);
  }
  long extra_points() const override { return options.enabled ? options.max_points : 0; }
  template <typename Scalar>
  static std::unique_ptr<TrainingStrategy<Scalar>> make(const AdaptiveOptions& o, const Problem& problem,
                                                        const std::vector<std::string>& names) {
    const std::size_t term = residual_term_for("adaptive", problem, names);
    return std::make_unique<AdaptiveRefinement<Scalar>>(o, term, names[term]);
  }
};

}  // namespace

std::unique_ptr<StrategySettings> make_adaptive_settings() { return std::make_unique<AdaptiveSettings>(); }

}  // namespace nfield::solvers
