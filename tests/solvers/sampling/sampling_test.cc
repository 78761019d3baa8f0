// SPDX-License-Identifier: MIT
//
// training.sampler, adaptive, balance and causal (solvers/sampling/random.h, loss_balancing.h):
// quasi-random points lie in the domain, cover faces and the initial slice, and integrate a
// smooth function far better than random points; RAR finds a localized source; grad_norm
// sets λ to max|∇L_pde| / mean|∇L_bc| at the parameters it saw; causal weights are
// exp(−ε · cumulative slice loss); a run using all of them resumes bit for bit; an epoch
// order's samples follow from their positions alone; bad values are config errors at their key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "solvers/training/adaptive_options.h"
#include "solvers/training/adaptive_refinement.h"
#include "solvers/training/causal_weighting.h"
#include "solvers/training/loss_balancing.h"
#include "solvers/run/run.h"
#include "solvers/sampling/epoch_order.h"
#include "solvers/sampling/random.h"
#include "solvers/training/trainer.h"
#include "tests/testing/resume_check.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

// The points RAR added so far, and the causal weights now: empty when the strategy is off.
template <typename Scalar>
Eigen::MatrixXd refined_points(const Trainer<Scalar>& trainer) {
  const auto* adaptive = trainer.template strategy<AdaptiveRefinement<Scalar>>();
  return adaptive ? adaptive->points() : Eigen::MatrixXd();
}
template <typename Scalar>
CausalWeights causal_weights_of(const Trainer<Scalar>& trainer) {
  const auto* causal = trainer.template strategy<CausalWeighting<Scalar>>();
  return causal ? causal->weights() : CausalWeights();
}

std::filesystem::path write_config(const std::string& text, const std::string& name = "config") {
  return testutil::write_config("solvers", text, name);
}

// ---- quasi-random sequences ------------------------------------------------------------

const Domain kBox({-1.0, 0.0}, {2.0, 0.5}, std::pair{0.0, 3.0});

// f = exp(x/2) cos(y) (1 + t²) over [−1, 2] × [0, 0.5] × [0, 3]: a smooth integrand.
double integrand(const Eigen::RowVectorXd& p) {
  return std::exp(0.5 * p(0)) * std::cos(p(1)) * (1 + p(2) * p(2));
}
double exact_mean() {
  const double ix = 2 * (std::exp(1.0) - std::exp(-0.5)), iy = std::sin(0.5), it = 3 + 9.0;
  return ix * iy * it / (3 * 0.5 * 3);
}

// Mean of the integrand over an interior batch of n, drawn with `sampler` and `seed`.
double batch_mean(const std::string& sampler, std::uint64_t seed, Eigen::Index n) {
  Random rng(seed);
  std::unique_ptr<UnitSequence> sequence;
  if (sampler != "uniform") sequence = std::make_unique<UnitSequence>(sampler, seed);
  const AttachSequence attach(rng, sequence.get());
  const Eigen::MatrixXd x = kBox.sample_interior(rng, n);
  double sum = 0;
  for (Eigen::Index r = 0; r < n; ++r) sum += integrand(x.row(r));
  return sum / n;
}

double rms_error(const std::string& sampler, Eigen::Index n) {
  double sum = 0;
  const int seeds = 16;
  for (int s = 0; s < seeds; ++s) sum += std::pow(batch_mean(sampler, 100 + s, n) - exact_mean(), 2);
  return std::sqrt(sum / seeds);
}

TEST(Sampler, QuasiRandomIntegratesFarBetterThanRandom) {
  const double uniform = rms_error("uniform", 1024);
  for (const std::string kind : {"sobol", "halton"}) {
    const double quasi = rms_error(kind, 1024);
    std::printf("rms error of the mean over 1024 points: uniform %.3e, %s %.3e\n", uniform,
                kind.c_str(), quasi);
    // Random points: error ~ σ/√N; low-discrepancy ones ~ (log N)³/N here. Measured at
    // N = 1024 over 16 seeds: uniform 0.16, sobol 0.006, halton 0.019; demand 5× at least.
    EXPECT_LT(quasi, 0.2 * uniform) << kind;
  }
}

TEST(Sampler, PointsStayInTheBoxAndBatchesContinueTheSequence) {
  for (const std::string kind : {"sobol", "halton"}) {
    Random rng(3);
    UnitSequence sequence(kind, 3);
    const AttachSequence attach(rng, &sequence);
    const Eigen::MatrixXd a = kBox.sample_interior(rng, 500);
    const Eigen::MatrixXd b = kBox.sample_interior(rng, 500);
    for (const Eigen::MatrixXd* x : {&a, &b})
      for (int c = 0; c < 3; ++c) {
        EXPECT_GE(x->col(c).minCoeff(), kBox.input_lower()(c)) << kind;
        EXPECT_LT(x->col(c).maxCoeff(), kBox.input_upper()(c)) << kind;
      }
    EXPECT_GT((a - b).cwiseAbs().maxCoeff(), 0.1) << kind << ": the second batch repeats the first";
    // The engine was not touched: only the sequence supplies the points.
    EXPECT_EQ(rng(), Random(3)());

    // Counts are the whole state: restoring them continues the same points.
    UnitSequence restored(kind, 3);
    restored.set_state(sequence.state());
    EXPECT_EQ(sequence.next(7, 3), restored.next(7, 3)) << kind;
    UnitSequence rewound(kind, 3);
    rewound.set_counts({{3, 500}});
    Random other(3);
    const AttachSequence attach_other(other, &rewound);
    EXPECT_EQ(kBox.sample_interior(other, 500), b) << kind;
    // Another seed gives another randomization.
    UnitSequence reseeded(kind, 4);
    EXPECT_GT((reseeded.next(100, 3) - UnitSequence(kind, 3).next(100, 3)).cwiseAbs().maxCoeff(), 0.01);
  }
}

TEST(Sampler, FacesAndInitialSliceAreCovered) {
  for (const std::string kind : {"sobol", "halton"}) {
    Random rng(1);
    UnitSequence sequence(kind, 9);
    const AttachSequence attach(rng, &sequence);
    const Eigen::MatrixXd x = kBox.sample_faces(kBox.faces(), rng, 4096);
    // Faces x_min, x_max have measure 0.5 each, y_min, y_max 3 each: shares 1/14, 1/14, 6/14, 6/14.
    std::vector<int> counts(4, 0);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      int on = -1;
      for (int f = 0; f < 4; ++f) {
        const Face face = kBox.faces()[f];
        const double bound = face.upper ? kBox.upper()[face.axis] : kBox.lower()[face.axis];
        if (x(r, face.axis) == bound) on = f;
      }
      ASSERT_GE(on, 0) << "point " << r << " is on no face";
      ++counts[on];
      EXPECT_GE(x(r, 2), 0.0);
      EXPECT_LT(x(r, 2), 3.0);
    }
    const double share[4] = {1 / 14.0, 1 / 14.0, 6 / 14.0, 6 / 14.0};
    for (int f = 0; f < 4; ++f) EXPECT_NEAR(counts[f] / 4096.0, share[f], 0.01) << kind << " face " << f;

    const Eigen::MatrixXd initial = kBox.sample_initial(rng, 1024);
    EXPECT_TRUE((initial.col(2).array() == 0.0).all());
    // Evenly spread in space: the mean of x within 1% of the box width of the middle.
    EXPECT_NEAR(initial.col(0).mean(), 0.5, 0.03) << kind;
    EXPECT_NEAR(initial.col(1).mean(), 0.25, 0.005) << kind;
  }
}

// ---- RAR ------------------------------------------------------------------------------

// A source concentrated at (0.7, 0.3): the residual of a nearly flat field is largest there.
constexpr const char* kLocalized = R"yaml(
problem: poisson
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: "1.0e4*exp(-((x - 0.7)^2 + (y - 0.3)^2)/0.002)"
conditions:
  - {on: boundary, type: dirichlet, value: "0"}
field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 1}
training:
  seed: 2
  threads: 1
  batch: {interior: 128, boundary: 32}
  sampler: SAMPLER
  adaptive: {every: 2, candidates: 4000, add: 30, max_points: 50}
  stages:
    - {optimizer: adam, steps: 5, lr: 1.0e-3}
    - {optimizer: lbfgs, steps: 2}
)yaml";

std::string with(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(Adaptive, AddsPointsWhereTheResidualPeaks) {
  for (const std::string sampler : {"uniform", "sobol"}) {
    RunSetup setup = load_run(write_config(with(kLocalized, "SAMPLER", sampler)), {});
    fields::Field<double> field(setup.field);
    Trainer<double> trainer(*setup.problem, field, setup.training);
    ASSERT_TRUE(trainer.run({}));
    // Refinements at steps 2 and 4 add 30 each; the cap keeps the newest 50.
    const Eigen::MatrixXd& extra = refined_points(trainer);
    ASSERT_EQ(extra.rows(), 50) << sampler;
    for (Eigen::Index r = 0; r < extra.rows(); ++r) {
      const double d = std::hypot(extra(r, 0) - 0.7, extra(r, 1) - 0.3);
      EXPECT_LT(d, 0.1) << sampler << " point " << r;
    }
    // The L-BFGS stage's fixed set is its batch followed by the extra set.
    const Eigen::MatrixXd& pde = trainer.points(0);
    ASSERT_EQ(pde.rows(), 128 + 50);
    EXPECT_EQ(Eigen::MatrixXd(pde.bottomRows(50)), extra);
    // Uniform candidates would land near the source in only ~π·0.1² ≈ 3% of cases.
    const auto metrics = trainer.extra_metrics();
    EXPECT_EQ(metrics.back().first, "adaptive_points");
    EXPECT_EQ(metrics.back().second, 50.0);
  }
}

TEST(Adaptive, LargestAndCappedAppend) {
  Eigen::VectorXd s(6);
  s << 1, 5, std::nan(""), 5, 9, -2;
  EXPECT_EQ(largest(s, 3), (std::vector<Eigen::Index>{4, 1, 3}));
  Eigen::MatrixXd set;
  append_capped(set, Eigen::MatrixXd::Constant(2, 2, 1.0), 3);
  append_capped(set, Eigen::MatrixXd::Constant(2, 2, 2.0), 3);
  ASSERT_EQ(set.rows(), 3);
  EXPECT_EQ(set(0, 0), 1.0);  // the oldest row left
  EXPECT_EQ(set(2, 0), 2.0);
}

// ---- grad_norm ------------------------------------------------------------------------

TEST(Balance, TargetIsMaxOverMean) {
  Eigen::VectorXd pde(3), term(4);
  pde << 1, -4, 2;
  term << 0.5, -0.5, 1, 0;
  EXPECT_DOUBLE_EQ(grad_norm_target(pde, term.head(3), 2.0, 7.0), 2.0 * 4 / (2.0 / 3));
  EXPECT_EQ(grad_norm_target(pde, Eigen::VectorXd::Zero(3), 2.0, 7.0), 7.0);  // no gradient: keep
}

// The Poisson source is large (gradients of L_pde ~ 10⁴ × those of the boundary term). With
// α = 1 and an update at step 0, λ_bc after one step must equal max|∇L_pde| / mean|∇L_bc| at
// the initial parameters and points, which this test recomputes independently.
TEST(Balance, GradNormSetsLambdaFromGradientScales) {
  const std::string text = with(with(with(kLocalized, "SAMPLER", "uniform"),
                                     "  adaptive: {every: 2, candidates: 4000, add: 30, max_points: 50}\n",
                                     "  balance: {method: grad_norm, every: 1, alpha: 1}\n"),
                                "    - {optimizer: lbfgs, steps: 2}\n", "");
  RunSetup setup = load_run(write_config(with(text, "steps: 5", "steps: 1")), {});
  fields::Field<double> field(setup.field);
  const fields::Field<double> initial(setup.field);  // the same seed: the same θ₀
  ASSERT_EQ(initial.parameters(), field.parameters());
  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));

  const auto terms = setup.problem->loss_terms();
  std::vector<Eigen::VectorXd> g;
  for (size_t k = 0; k < terms.size(); ++k) {
    const Eigen::MatrixXd& x = trainer.points(k);
    const auto residual = terms[k].residual(x);
    const ResidualLoss<double> loss(*residual, terms[k].weight, x.rows());
    Eigen::VectorXd gradient = Eigen::VectorXd::Zero(initial.parameter_count());
    initial.network().value_and_gradient(initial.parameters().data(), autodiff::StreamLayout(terms[k].spec),
                                         x, loss, gradient.data());
    g.push_back(gradient);
  }
  const double expected = g[0].cwiseAbs().maxCoeff() / g[1].cwiseAbs().mean();
  EXPECT_GT(expected, 100.0);  // the terms really are unbalanced
  ASSERT_EQ(trainer.balance_weights().size(), 2u);
  EXPECT_EQ(trainer.balance_weights()[0], 1.0);
  EXPECT_NEAR(trainer.balance_weights()[1], expected, 1e-9 * expected);
  // After the update the weighted boundary gradient is on the PDE gradient's scale.
  const double ratio = g[0].cwiseAbs().maxCoeff() / (trainer.balance_weights()[1] * g[1].cwiseAbs().mean());
  EXPECT_NEAR(ratio, 1.0, 1e-9);
}

// With α = 0.5 and updates every step, λ moves from 1 toward λ̂ (> 100) monotonically at
// first: after 4 steps it is well above 1 but still an average, not a jump.
TEST(Balance, GradNormMovesTowardBalance) {
  const std::string text = with(with(with(kLocalized, "SAMPLER", "uniform"),
                                     "  adaptive: {every: 2, candidates: 4000, add: 30, max_points: 50}\n",
                                     "  balance: {method: grad_norm, every: 1, alpha: 0.5}\n"),
                                "    - {optimizer: lbfgs, steps: 2}\n", "");
  std::vector<double> lambdas;
  for (int steps = 1; steps <= 4; ++steps) {
    RunSetup setup = load_run(write_config(with(text, "steps: 5", "steps: " + std::to_string(steps))), {});
    fields::Field<double> field(setup.field);
    Trainer<double> trainer(*setup.problem, field, setup.training);
    ASSERT_TRUE(trainer.run({}));
    lambdas.push_back(trainer.balance_weights()[1]);
  }
  EXPECT_GT(lambdas[0], 10.0);
  for (size_t i = 1; i < lambdas.size(); ++i) EXPECT_GT(lambdas[i], lambdas[i - 1]);
}

// ---- causal ---------------------------------------------------------------------------

TEST(Causal, WeightsFromCumulativeSliceLosses) {
  Eigen::VectorXd t(5), r2(5);
  t << 0.1, 0.3, 0.35, 0.9, 1.0;
  r2 << 1, 2, 4, 8, 6;
  const CausalWeights c = causal_weights(t, r2, 0.0, 1.0, 4, 0.5);
  // Slices [0, .25): {1}; [.25, .5): {2, 4}; [.5, .75): none; [.75, 1]: {8, 6} (t1 closes it).
  ASSERT_EQ(c.slice_losses, (std::vector<double>{1, 3, 0, 7}));
  const std::vector<double> want{1, std::exp(-0.5), std::exp(-0.5 * 4), std::exp(-0.5 * 4)};
  for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(c.weights[i], want[i]) << i;
  for (int i = 1; i < 4; ++i) EXPECT_LE(c.weights[i], c.weights[i - 1]);
  EXPECT_DOUBLE_EQ(c.min_weight(), std::exp(-2.0));
  // Per point N cᵢ/(M nᵢ): then w/N Σ aₙ r²ₙ = (w/M) Σ cᵢ Lᵢ.
  EXPECT_DOUBLE_EQ(c.point_weights(0), 5.0 * want[0] / (4 * 1));
  EXPECT_DOUBLE_EQ(c.point_weights(1), 5.0 * want[1] / (4 * 2));
  EXPECT_DOUBLE_EQ(c.point_weights(4), 5.0 * want[3] / (4 * 2));
  const double weighted = (c.point_weights.array() * r2.array()).sum() / 5;
  EXPECT_DOUBLE_EQ(weighted, (want[0] * 1 + want[1] * 3 + want[3] * 7) / 4);
  // ε = 0: plain mean over slices.
  const CausalWeights flat = causal_weights(t, r2, 0.0, 1.0, 4, 0.0);
  EXPECT_EQ(flat.min_weight(), 1.0);
}

constexpr const char* kWave = R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation:
  speed: 2
  exact: "sin(pi*x)*cos(2*pi*t)"
conditions:
  - {on: boundary, type: dirichlet, value: "0", weight: 10}
  - {on: initial, type: value, value: "sin(pi*x)", weight: 10}
  - {on: initial, type: velocity, value: "0", weight: 10}
field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 1}
training:
  seed: 4
  threads: 2
  batch: {interior: 256, boundary: 32, initial: 32}
  resample_every: 3
  sampler: sobol
  adaptive: {every: 5, candidates: 500, add: 10, max_points: 25}
  balance: {method: grad_norm, every: 3, alpha: 0.3}
  causal: {epsilon: 0.01, slices: 8}
  stages:
    - {optimizer: adam, steps: 20, lr: 3.0e-3, schedule: cosine, lr_final: 1.0e-4}
)yaml";

// The trainer's causal weights are those of its PDE points at the parameters of the step.
TEST(Causal, TrainerWeightsMatchTheLossesOfItsPoints) {
  RunSetup setup = load_run(write_config(with(kWave, "steps: 20", "steps: 1")), {});
  fields::Field<double> field(setup.field);
  const fields::Field<double> initial(setup.field);  // the same seed: the same θ₀
  ASSERT_EQ(initial.parameters(), field.parameters());
  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  const Eigen::MatrixXd& x = trainer.points(0);
  const LossTerm pde = setup.problem->loss_terms()[0];
  const autodiff::StreamLayout layout(pde.spec);
  autodiff::Streams<double> out;
  initial.evaluate(layout, x, out);
  Eigen::MatrixXd r;
  pde.residual(x)->evaluate(0, layout, out, r);
  const CausalWeights want = causal_weights(x.col(1), r.rowwise().squaredNorm(), 0, 1, 8, 0.01);
  EXPECT_EQ(causal_weights_of(trainer).weights, want.weights);
  EXPECT_LT(want.min_weight(), 0.999);  // the weights do something here
  EXPECT_EQ(trainer.extra_metrics().front().first, "causal_min_weight");
}

// L-BFGS runs in segments of `every` iterations when causal or adaptive is on: after each,
// the extra set is refined and the causal weights recomputed at the parameters reached.
TEST(Causal, LbfgsSegmentsUpdateWeightsAndExtraSet) {
  const std::string text = with(with(kWave, "    - {optimizer: adam, steps: 20, lr: 3.0e-3, schedule: cosine, lr_final: 1.0e-4}\n",
                                     "    - {optimizer: adam, steps: 4, lr: 3.0e-3}\n    - {optimizer: lbfgs, steps: LBFGS}\n"),
                                "slices: 8}", "slices: 8, every: 5}");
  auto train = [&](int lbfgs_steps, fields::Field<double>& field) {
    RunSetup setup = load_run(write_config(with(text, "LBFGS", std::to_string(lbfgs_steps)),
                                           "lbfgs" + std::to_string(lbfgs_steps)), {});
    auto trainer = std::make_unique<Trainer<double>>(*setup.problem, field, setup.training);
    EXPECT_TRUE(trainer->run({}));
    return std::make_pair(std::move(setup), std::move(trainer));
  };
  RunSetup base = load_run(write_config(with(text, "LBFGS", "1"), "base"), {});
  fields::Field<double> at10(base.field), at12(base.field);
  auto [setup10, ten] = train(10, at10);
  auto [setup12, twelve] = train(12, at12);
  EXPECT_EQ(twelve->step(), 16);
  // Refinements after L-BFGS iterations 5 and 10 (none in the 4 Adam steps).
  ASSERT_EQ(refined_points(*twelve).rows(), 20);
  EXPECT_EQ(refined_points(*ten).rows(), 10);
  const Eigen::MatrixXd& x = twelve->points(0);
  ASSERT_EQ(x.rows(), 256 + 20);
  EXPECT_EQ(Eigen::MatrixXd(x.bottomRows(20)), refined_points(*twelve));
  EXPECT_EQ(Eigen::MatrixXd(x.topRows(256)), Eigen::MatrixXd(ten->points(0).topRows(256)));
  // The run of 12 updated its weights after iteration 10, at the parameters the run of 10 ended with.
  const LossTerm pde = setup12.problem->loss_terms()[0];
  const autodiff::StreamLayout layout(pde.spec);
  autodiff::Streams<double> out;
  at10.evaluate(layout, x, out);
  Eigen::MatrixXd r;
  pde.residual(x)->evaluate(0, layout, out, r);
  const CausalWeights want = causal_weights(x.col(1), r.rowwise().squaredNorm(), 0, 1, 8, 0.01);
  EXPECT_EQ(causal_weights_of(*twelve).weights, want.weights);
  EXPECT_NE(causal_weights_of(*twelve).weights, causal_weights_of(*ten).weights);
}

// ---- checkpoint round trip ------------------------------------------------------------

TEST(SamplingState, ResumedRunWithEverythingOnIsBitExact) {
  for (const std::string sampler : {"sobol", "halton"}) {
    SCOPED_TRACE(sampler);
    const auto path = write_config(with(kWave, "sampler: sobol", "sampler: " + sampler), sampler);
    const RunSetup setup = load_run(path, {});
    // Step 7: after a refinement (5) and a balance update (6), between resamples (6, 9).
    ASSERT_NO_FATAL_FAILURE(testutil::expect_resume_is_bit_exact<float>(
        setup, path.parent_path() / (sampler + ".h5"), 7, [](const testutil::FinishedRuns<float>& runs) {
          EXPECT_EQ(refined_points(runs.resumed), refined_points(runs.whole));
          EXPECT_EQ(refined_points(runs.resumed).rows(), 25);  // 3 refinements of 10, capped
          EXPECT_EQ(runs.resumed.balance_weights(), runs.whole.balance_weights());
          EXPECT_NE(runs.whole.balance_weights()[1], 1.0);
          EXPECT_EQ(causal_weights_of(runs.resumed).weights, causal_weights_of(runs.whole).weights);
        }));
  }
}

// ---- config ---------------------------------------------------------------------------

void expect_error(const std::string& text, const std::string& key_path, const std::string& part) {
  const auto path = write_config(text, "bad");
  try {
    load_run(path, {});
    ADD_FAILURE() << "no error for " << key_path;
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_GT(e.line(), 0) << e.what();
    EXPECT_EQ(e.key_path(), key_path) << e.what();
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(SamplingConfig, BadValuesAreConfigErrors) {
  expect_error(with(kWave, "sampler: sobol", "sampler: sobel"), "training.sampler", "uniform, sobol, halton");
  expect_error(with(kWave, "add: 10", "add: 1000"), "training.adaptive.add", "500");
  expect_error(with(kWave, "every: 5,", "evry: 5,"), "training.adaptive.evry",
               "unknown key 'evry'");
  expect_error(with(kWave, "alpha: 0.3", "alpha: 0"), "training.balance.alpha", "alpha in (0, 1]");
  expect_error(with(kWave, "method: grad_norm", "method: softadapt"), "training.balance.method", "grad_norm");
  expect_error(with(kWave, "balance: {method: grad_norm, every: 3, alpha: 0.3}", "balance: gradnorm"),
               "training.balance", "fixed, grad_norm");
  expect_error(with(kWave, "slices: 8", "slices: 0"), "training.causal.slices", "");
  expect_error(with(kWave, "epsilon: 0.01", "epsilon: -1"), "training.causal.epsilon", "");
  // Causal weighting on a problem without time.
  expect_error(with(with(kLocalized, "SAMPLER", "halton"), "  adaptive:", "  causal: {epsilon: 1}\n  adaptive:"),
               "training.causal", "time axis");
}

TEST(SamplingConfig, ResolvedConfigKeepsTheKeys) {
  const RunSetup first = load_run(write_config(kWave), {});
  const std::string text = io::to_yaml(first.resolved);
  for (const char* key : {"sampler: sobol", "adaptive:", "max_points: 25", "method: grad_norm",
                          "alpha: 0.3", "epsilon: 0.01", "slices: 8"})
    EXPECT_NE(text.find(key), std::string::npos) << key << " in\n" << text;
  const RunSetup again = load_run(write_config(text, "again"), {});
  EXPECT_EQ(io::to_yaml(again.resolved), text);
  // Defaults: uniform and fixed are written; adaptive and causal stay off.
  const RunSetup plain = load_run(write_config(with(with(with(with(kWave, "  sampler: sobol\n", ""),
      "  adaptive: {every: 5, candidates: 500, add: 10, max_points: 25}\n", ""),
      "  balance: {method: grad_norm, every: 3, alpha: 0.3}\n", ""),
      "  causal: {epsilon: 0.01, slices: 8}\n", ""), "plain"), {});
  const std::string defaults = io::to_yaml(plain.resolved);
  EXPECT_NE(defaults.find("sampler: uniform"), std::string::npos);
  EXPECT_NE(defaults.find("balance: fixed"), std::string::npos);
  EXPECT_EQ(defaults.find("causal"), std::string::npos);
  EXPECT_EQ(plain.training.strategy_options<AdaptiveOptions>(), nullptr);
  EXPECT_FALSE(plain.training.has_strategies());
}

// Positions past the first epoch, asked out of order, give what asking in order gives: the
// order is a function of the position alone. (Fit's draws: tests/solvers/problems/fit_test.cc.)
TEST(EpochOrder, APositionsSampleDoesNotDependOnWhatWasAskedBefore) {
  const EpochOrder order(7, 11);
  const Eigen::VectorXi in_order = order.at(0, 30);
  const EpochOrder fresh(7, 11);
  EXPECT_EQ(fresh.at(23, 5), in_order.segment(23, 5));
  EXPECT_EQ(fresh.at(2, 4), in_order.segment(2, 4));
  for (int e = 0; e < 4; ++e) {
    std::vector<int> epoch(in_order.data() + 7 * e, in_order.data() + 7 * e + 7);
    std::sort(epoch.begin(), epoch.end());
    for (int k = 0; k < 7; ++k) EXPECT_EQ(epoch[static_cast<size_t>(k)], k) << "epoch " << e;
  }
  EXPECT_THROW(EpochOrder(0, 1), std::invalid_argument);
  EXPECT_THROW(order.at(-1, 1), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::solvers
