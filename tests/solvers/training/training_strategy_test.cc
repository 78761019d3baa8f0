// SPDX-License-Identifier: MIT
//
// The training strategies (solvers/training/training_strategy.h) one at a time, on terms
// made up here instead of a trainer's: grad_norm's moving average of λ against a hand
// computation, the causal weights of a toy residual, RAR's extra set as it is refined, joined
// and capped; each one's checkpoint round trip; the registry of strategies (each reads its
// own key of `training:`). The runs through the trainer are in sampling_test.cc.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "io/hdf5_file.h"
#include "io/registry.h"
#include "solvers/training/adaptive_refinement.h"
#include "solvers/training/causal_weighting.h"
#include "solvers/training/communicator.h"
#include "solvers/training/gradient_balancing.h"
#include "solvers/training/strategy_settings.h"
#include "solvers/training/training_options.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

// Terms with fixed gradients and squared residuals. term_loss(k, w) is w·losses[k] with
// gradient w·gradients[k]; sample hands out `candidates` in turn.
class FakeView final : public StrategyView<double> {
 public:
  long step() const override { return step_; }
  double term_weight(std::size_t k) const override { return weights.at(k); }
  const TermPoints& points(std::size_t k) const override { return term_points.at(k); }
  Eigen::Index parameter_count() const override { return gradients.at(0).size(); }
  Communicator& communicator() const override { return serial_; }
  TermPoints sample(std::size_t k, Eigen::Index n) override {
    EXPECT_EQ(k, sampled_term);
    EXPECT_EQ(n, candidates.at(draws).x.rows());
    return candidates.at(draws++);
  }
  Eigen::VectorXd squared_residuals(std::size_t k) const override {
    return squared_residuals(k, term_points.at(k));
  }
  Eigen::VectorXd squared_residuals(std::size_t k, const TermPoints& p) const override {
    return score(k, p.x);
  }
  void replace_points(std::size_t k, Eigen::MatrixXd x) override { term_points.at(k).x = std::move(x); }
  double term_loss(std::size_t k, double weight, double* gradient) override {
    Eigen::Map<Eigen::VectorXd>(gradient, parameter_count()) += weight * gradients.at(k);
    return weight * losses.at(k);
  }
  void set_term_loss(std::size_t k, double loss) override { set_losses.at(k) = loss; }

  long step_ = 0;
  std::vector<double> weights;
  std::vector<Eigen::VectorXd> gradients;
  std::vector<double> losses, set_losses;
  std::vector<TermPoints> term_points;
  std::function<Eigen::VectorXd(std::size_t, const Eigen::MatrixXd&)> score;
  std::vector<TermPoints> candidates;
  std::size_t sampled_term = 0;
  std::size_t draws = 0;

 private:
  mutable SerialCommunicator serial_;
};

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(v.size());
  std::copy(v.begin(), v.end(), out.data());
  return out;
}

// Writes `strategy`'s state to a checkpoint and loads it into `into`.
void round_trip(const TrainingStrategy<double>& strategy, TrainingStrategy<double>& into) {
  const auto path = testutil::scratch_dir("solvers") / "state.h5";
  {
    io::H5Writer file(path);
    file.create_group("trainer");
    strategy.save(file, "trainer");
    file.commit();
  }
  into.load(io::H5Reader(path), "trainer");
}

// ---- grad_norm ---------------------------------------------------------------------------

TEST(GradientBalancing, MovingAverageOfLambdaByHand) {
  FakeView view;
  view.weights = {1, 2, 3};
  view.gradients = {vec({1, -4, 2}), vec({0.5, -0.5, 1}), vec({0, 0.2, -0.1})};
  view.losses = {10, 20, 30};
  view.set_losses.assign(3, 0);
  BalanceOptions options;
  options.method = "grad_norm";
  options.every = 2;
  options.alpha = 0.25;
  GradientBalancing<double> balance(options, 0, {"pde", "bc", "ic"});
  for (int k = 0; k < 3; ++k) EXPECT_EQ(balance.loss_scale(k), 1.0);

  // Not an update step: the trainer takes the gradient.
  Eigen::VectorXd g(3);
  view.step_ = 1;
  EXPECT_FALSE(balance.step_gradient(view, g.data()));

  // λ̂ₖ = wₖ max|w₀g₀| / mean|wₖgₖ|: max|g₀| = 4; mean|2g₁| = 4/3, mean|3g₂| = 0.3.
  const double target1 = 2 * 4 / (4.0 / 3), target2 = 3 * 4 / 0.3;  // 6, 40
  double lambda1 = 1, lambda2 = 1;
  for (long step : {0L, 2L}) {
    view.step_ = step;
    ASSERT_TRUE(balance.step_gradient(view, g.data()));
    lambda1 = 0.75 * lambda1 + 0.25 * target1;
    lambda2 = 0.75 * lambda2 + 0.25 * target2;
    EXPECT_EQ(balance.loss_scale(0), 1.0);
    EXPECT_DOUBLE_EQ(balance.loss_scale(1), lambda1) << "step " << step;
    EXPECT_DOUBLE_EQ(balance.loss_scale(2), lambda2) << "step " << step;
    // The step's gradient and losses are the balanced ones: Σ λₖ wₖ gₖ, λₖ wₖ Lₖ.
    const Eigen::VectorXd want =
        view.gradients[0] + lambda1 * 2 * view.gradients[1] + lambda2 * 3 * view.gradients[2];
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(g(i), want(i), 1e-12 * (1 + std::abs(want(i))));
    EXPECT_EQ(view.set_losses[0], 10.0);
    EXPECT_DOUBLE_EQ(view.set_losses[1], 40 * lambda1);
    EXPECT_DOUBLE_EQ(view.set_losses[2], 90 * lambda2);
  }
  EXPECT_DOUBLE_EQ(lambda1, 3.1875);  // 0.75 (0.75 + 1.5) + 1.5
  EXPECT_DOUBLE_EQ(lambda2, 18.0625);

  std::vector<std::pair<std::string, double>> metrics;
  balance.metrics(metrics);
  ASSERT_EQ(metrics.size(), 3u);
  EXPECT_EQ(metrics[1].first, "balance_weight_bc");
  EXPECT_EQ(metrics[1].second, balance.loss_scale(1));

  GradientBalancing<double> resumed(options, 0, {"pde", "bc", "ic"});
  round_trip(balance, resumed);
  EXPECT_EQ(resumed.weights(), balance.weights());
  // λ of another term count is not this run's.
  GradientBalancing<double> other(options, 0, {"pde", "bc"});
  round_trip(balance, other);
  EXPECT_EQ(other.weights(), (std::vector<double>{1, 1}));
}

// ---- causal ------------------------------------------------------------------------------

TEST(CausalWeighting, WeightsOfAToyResidual) {
  FakeView view;
  // Term 1 is the residual term, over (x, t); term 0 something else.
  Eigen::MatrixXd x(5, 2);
  x << 0, 0.1, 0, 0.3, 0, 0.35, 0, 0.9, 0, 1.0;
  view.term_points = {TermPoints(Eigen::MatrixXd::Zero(5, 2)), TermPoints(x)};
  const Eigen::VectorXd r2 = vec({1, 2, 4, 8, 6});
  view.score = [&](std::size_t k, const Eigen::MatrixXd&) {
    EXPECT_EQ(k, 1u);
    return r2;
  };
  CausalOptions options;
  options.enabled = true;
  options.slices = 4;
  options.epsilon = 0.5;
  options.every = 7;
  CausalWeighting<double> causal(options, 1, 1, 0.0, 1.0);
  EXPECT_EQ(causal.point_weights(1, view.points(1)), nullptr);  // before the first update
  std::vector<std::pair<std::string, double>> shown;
  causal.progress(shown);
  EXPECT_TRUE(shown.empty());

  causal.update_weights(view);
  // Slices [0, .25): {1}; [.25, .5): {2, 4}; [.5, .75): none; [.75, 1]: {8, 6}. Mean losses
  // 1, 3, 0, 7: cᵢ = exp(−0.5 · (0, 1, 4, 4)).
  const std::vector<double> c{1, std::exp(-0.5), std::exp(-2.0), std::exp(-2.0)};
  ASSERT_EQ(causal.weights().weights.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(causal.weights().weights[i], c[i]) << i;
  // aₙ = N cᵢ / (M nᵢ) on the residual term only, and only for the points they were made for.
  const Eigen::VectorXd* a = causal.point_weights(1, view.points(1));
  ASSERT_NE(a, nullptr);
  const std::vector<double> want{5 * c[0] / 4, 5 * c[1] / 8, 5 * c[1] / 8, 5 * c[3] / 8, 5 * c[3] / 8};
  for (int n = 0; n < 5; ++n) EXPECT_DOUBLE_EQ((*a)(n), want[n]) << n;
  EXPECT_EQ(causal.point_weights(0, view.points(0)), nullptr);
  EXPECT_EQ(causal.point_weights(1, TermPoints(Eigen::MatrixXd::Zero(6, 2))), nullptr);
  // No factor on the term's loss; segments of L-BFGS (reweighted) at most `every` long.
  EXPECT_EQ(causal.loss_scale(1), 1.0);
  EXPECT_EQ(causal.segment_limit(true), 7);
  EXPECT_EQ(causal.segment_limit(false), INT_MAX);

  std::vector<std::pair<std::string, double>> metrics;
  causal.metrics(metrics);
  causal.progress(shown);
  ASSERT_EQ(metrics.size(), 1u);
  EXPECT_EQ(metrics[0].first, "causal_min_weight");
  EXPECT_DOUBLE_EQ(metrics[0].second, std::exp(-2.0));
  ASSERT_EQ(shown.size(), 1u);
  EXPECT_EQ(shown[0].first, "causal min w");

  // The checkpoint keeps the cᵢ; the aₙ come with the next update.
  CausalWeighting<double> resumed(options, 1, 1, 0.0, 1.0);
  round_trip(causal, resumed);
  EXPECT_EQ(resumed.weights().weights, causal.weights().weights);
  EXPECT_EQ(resumed.point_weights(1, view.points(1)), nullptr);
}

// ---- RAR ---------------------------------------------------------------------------------

TEST(AdaptiveRefinement, SetIsRefinedJoinedAndCapped) {
  FakeView view;
  // Candidates (c, 10 + c); the score is the first coordinate, so the largest ones win.
  auto rows = [](std::initializer_list<double> firsts) {
    Eigen::MatrixXd x(firsts.size(), 2);
    int r = 0;
    for (double f : firsts) x.row(r++) << f, 10 + f;
    return TermPoints(x);
  };
  view.candidates = {rows({3, 9, 1, 7, 2, 5}), rows({8, 0, 6, 4, 1, 2})};
  view.score = [](std::size_t, const Eigen::MatrixXd& x) { return Eigen::VectorXd(x.col(0)); };
  AdaptiveOptions options;
  options.enabled = true;
  options.every = 3;
  options.candidates = 6;
  options.add = 2;
  options.max_points = 3;
  AdaptiveRefinement<double> adaptive(options, 0, "pde");
  EXPECT_EQ(adaptive.segment_limit(false), 3);

  // Not at step 0 nor between multiples of `every`.
  for (long step : {0L, 1L, 4L}) {
    view.step_ = step;
    EXPECT_FALSE(adaptive.before_step(view)) << step;
  }
  EXPECT_EQ(view.draws, 0u);
  view.step_ = 3;
  ASSERT_TRUE(adaptive.before_step(view));  // the step must draw anew
  EXPECT_EQ(adaptive.points(), Eigen::MatrixXd(rows({9, 7}).x));

  // Freshly drawn points of the residual term get the set behind them; others do not.
  TermPoints drawn = rows({-1, -2});
  adaptive.points_drawn(0, drawn);
  EXPECT_EQ(drawn.x, Eigen::MatrixXd(rows({-1, -2, 9, 7}).x));
  TermPoints other = rows({-3});
  adaptive.points_drawn(1, other);
  EXPECT_EQ(other.x.rows(), 1);
  TermPoints rays = rows({-4});
  rays.groups = {0, 1};
  EXPECT_THROW(adaptive.points_drawn(0, rays), std::logic_error);

  // Between segments of a stage that keeps its points: refine, then the stage's own points
  // followed by the new set (the oldest point, 9, left at the cap of 3).
  view.term_points = {drawn};
  adaptive.between_segments(view, false);
  EXPECT_EQ(adaptive.points(), Eigen::MatrixXd(rows({7, 8, 6}).x));
  EXPECT_EQ(view.points(0).x, Eigen::MatrixXd(rows({-1, -2, 7, 8, 6}).x));
  EXPECT_EQ(view.draws, 2u);

  std::vector<std::pair<std::string, double>> metrics;
  adaptive.metrics(metrics);
  ASSERT_EQ(metrics.size(), 1u);
  EXPECT_EQ(metrics[0], (std::pair<std::string, double>{"adaptive_points", 3}));

  AdaptiveRefinement<double> resumed(options, 0, "pde");
  round_trip(adaptive, resumed);
  EXPECT_EQ(resumed.points(), adaptive.points());
}

// The registry: hook order, one settings object per key that reads its own options, and
// what the run learns of a strategy without its name (the points it adds).
TEST(StrategyRegistry, EachStrategyReadsItsOwnKeyInHookOrder) {
  const std::vector<std::string> names = training_strategy_names();
  ASSERT_GE(names.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 3),
            (std::vector<std::string>{"causal", "balance", "adaptive"}));
  const TrainingOptions off = TrainingOptions::from_config(io::parse_config("seed: 1\n", "off.yaml"));
  ASSERT_EQ(off.strategies.size(), names.size());
  EXPECT_FALSE(off.has_strategies());
  for (const auto& s : off.strategies) EXPECT_EQ(s->extra_points(), 0) << s->key;

  const TrainingOptions on = TrainingOptions::from_config(io::parse_config(
      "adaptive: {every: 5, candidates: 500, add: 10, max_points: 25}\n"
      "balance: {method: grad_norm, every: 3, alpha: 0.3}\n",
      "on.yaml"));
  EXPECT_TRUE(on.has_strategies());
  ASSERT_NE(on.strategy_options<AdaptiveOptions>(), nullptr);
  EXPECT_EQ(on.strategy_options<AdaptiveOptions>()->max_points, 25);
  ASSERT_NE(on.strategy_options<BalanceOptions>(), nullptr);
  EXPECT_EQ(on.strategy_options<BalanceOptions>()->alpha, 0.3);
  EXPECT_EQ(on.strategy_options<CausalOptions>(), nullptr);  // off
  long extra = 0;
  for (const auto& s : on.strategies) extra += s->extra_points();
  EXPECT_EQ(extra, 25);
  // Written back under their keys, and read again alike.
  const YAML::Node written = on.to_yaml();
  EXPECT_EQ(written["adaptive"]["max_points"].as<long>(), 25);
  EXPECT_EQ(written["balance"]["method"].as<std::string>(), "grad_norm");
  EXPECT_FALSE(written["causal"]);
}

TEST(StrategyRegistry, UnknownKeysListTheValidOnesAndKeysAreNotTakenTwice) {
  try {
    make_strategy_settings("annealing");
    FAIL() << "no error";
  } catch (const UnknownNameError& e) {
    const std::string message = e.what();
    for (const char* name : {"causal", "balance", "adaptive"})
      EXPECT_NE(message.find(name), std::string::npos) << message;
  }
  EXPECT_EQ(make_strategy_settings("Causal")->key, "causal");  // case-insensitive
  EXPECT_THROW(register_training_strategy("balance", make_balance_settings), std::logic_error);
}

}  // namespace
}  // namespace nfield::solvers
