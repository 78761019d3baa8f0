// SPDX-License-Identifier: MIT
//
// load_run (solvers/run/run.h) below the program: bad configs raise io::ConfigError (never
// another exception) with file, line, column and key path; the resolved config reads back
// to itself; and the trainer's saved state resumes an interrupted Adam run bit for bit.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "solvers/output/grid_output.h"
#include "solvers/problems/problems.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

std::filesystem::path scratch_dir() { return testutil::scratch_dir("solvers"); }

std::filesystem::path write_config(const std::string& text) { return testutil::write_config("solvers", text); }

constexpr const char* kPoisson =
    "problem: poisson\n"                                   // 1
    "domain: {lower: [0, 0], upper: [1, 1]}\n"             // 2
    "equation:\n"                                          // 3
    "  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n"          // 4
    "  exact: \"sin(pi*x)*sin(pi*y)\"\n"                   // 5
    "conditions:\n"                                        // 6
    "  - {on: boundary, type: dirichlet, value: \"0\"}\n"  // 7
    "field: {type: siren, hidden: [8, 8], first_omega: 3, hidden_omega: 1}\n"  // 8
    "training:\n"                                          // 9
    "  seed: 5\n"                                          // 10
    "  threads: 1\n"                                       // 11
    "  batch: {interior: 64, boundary: 32}\n"              // 12
    "  resample_every: 3\n"                                // 13
    "  stages:\n"                                          // 14
    "    - {optimizer: adam, steps: 20, lr: 3.0e-3, schedule: cosine, lr_final: 1.0e-4}\n"  // 15
    "output: {grid: [5, 5]}\n";                            // 16

std::string replaced(const std::string& from, const std::string& to) {
  std::string text = kPoisson;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

using testutil::Located;

void expect_config_error(const std::string& text, const Located& want) {
  testutil::expect_located_error(write_config(text), want);
}

TEST(LoadRun, ExpressionInValueListIsAConfigError) {
  // Column 45: the opening quote of the list element.
  expect_config_error(replaced("value: \"0\"}", "value: [\"sin(pi*x\"]}"),
                      {7, 45, "conditions[0].value[0]", "in expression 'sin(pi*x'"});
}

TEST(LoadRun, EmptyFaceListIsAConfigError) {
  expect_config_error(replaced("on: boundary", "on: []"),
                      {7, 10, "conditions[0].on", "expected a face name"});
}

TEST(LoadRun, ResolvedConfigReadsBackToItself) {
  const RunSetup first = load_run(write_config(kPoisson), {});
  const std::string text = io::to_yaml(first.resolved);
  const auto again_path = scratch_dir() / "resolved.yaml";
  std::ofstream(again_path) << text;
  const RunSetup again = load_run(again_path, {});
  EXPECT_EQ(io::to_yaml(again.resolved), text);
  EXPECT_EQ(again.training.total_steps(), 20);
  EXPECT_EQ(again.output.grid, (std::vector<int>{5, 5}));
}

// ---- sine frequencies by problem ----------------------------------------------------

// A field config that names no first_omega or hidden_omega gets the problem's: 10 and 1 for an
// equation (Poisson, `problem: pde`), SIREN's 30 and 30 for a signal fit (autoint_1d); a
// value the config names wins.
fields::FieldOptions field_of(const std::string& text) { return load_run(write_config(text), {}).field; }

TEST(SineDefaults, EquationsStartAtTenAndOne) {
  const std::string siren = "field: {type: siren, hidden: [8, 8]}\n";
  const std::string line = "field: {type: siren, hidden: [8, 8], first_omega: 3, hidden_omega: 1}\n";
  fields::FieldOptions poisson = field_of(replaced(line, siren));
  EXPECT_EQ(poisson.first_omega, 10.0);
  EXPECT_EQ(poisson.hidden_omega, 1.0);
  // A sine MLP reads hidden_omega on every layer: sin(Wx + b), DeepXDE's "sin".
  poisson = field_of(replaced(line, "field: {type: mlp, activation: sine, hidden: [8]}\n"));
  EXPECT_EQ(poisson.hidden_omega, 1.0);
  poisson = field_of(replaced(line, "field: {type: siren, hidden: [8, 8], first_omega: 3}\n"));
  EXPECT_EQ(poisson.first_omega, 3.0);
  EXPECT_EQ(poisson.hidden_omega, 1.0);
  const fields::FieldOptions pde = field_of(
      "problem: pde\n"
      "domain: {lower: [0], upper: [1]}\n"
      "equation: {residuals: [\"u_xx + 1\"]}\n"
      "conditions: [{on: boundary, type: dirichlet, value: \"0\"}]\n"
      "field: {type: siren, hidden: [8, 8]}\n"
      "training: {stages: [{optimizer: adam, steps: 1}]}\n");
  EXPECT_EQ(pde.first_omega, 10.0);
  EXPECT_EQ(pde.hidden_omega, 1.0);
}

TEST(SineDefaults, SignalFitsKeepSirensThirty) {
  const std::string autoint =
      "problem: autoint_1d\n"
      "domain: {lower: [-1], upper: [1]}\n"
      "equation: {integrand: \"cos(10*x)\", antiderivative: \"sin(10*x)/10\", intervals: 100}\n"
      "field: {type: siren, hidden: [8, 8]SPEC}\n"
      "training: {stages: [{optimizer: adam, steps: 1}]}\n";
  auto with = [&](const std::string& spec) {
    std::string text = autoint;
    return field_of(text.replace(text.find("SPEC"), 4, spec));
  };
  fields::FieldOptions fit = with("");
  EXPECT_EQ(fit.first_omega, 30.0);
  EXPECT_EQ(fit.hidden_omega, 30.0);
  fit = with(", first_omega: 2, hidden_omega: 1");
  EXPECT_EQ(fit.first_omega, 2.0);
  EXPECT_EQ(fit.hidden_omega, 1.0);
}

// ---- trainer state -----------------------------------------------------------------

template <typename Scalar>
void expect_resume_bit_exact() {
  const auto path = write_config(kPoisson);
  RunSetup setup = load_run(path, {});
  const auto checkpoint = path.parent_path() / "state.h5";

  fields::Field<Scalar> full(setup.field);
  {
    Trainer<Scalar> trainer(*setup.problem, full, setup.training);
    ASSERT_TRUE(trainer.run({}));
    EXPECT_EQ(trainer.step(), 20);
  }

  // Stopped before step 8 (not a multiple of resample_every: the saved points matter).
  fields::Field<Scalar> first(setup.field);
  {
    Trainer<Scalar> trainer(*setup.problem, first, setup.training);
    typename Trainer<Scalar>::Callbacks callbacks;
    callbacks.stop_requested = [&trainer] { return trainer.step() >= 7; };
    ASSERT_FALSE(trainer.run(callbacks));
    EXPECT_EQ(trainer.step(), 7);
    io::H5Writer file(checkpoint);
    fields::save_field(file, first);
    trainer.save_state(file);
    file.commit();
  }
  EXPECT_FALSE(std::filesystem::exists(checkpoint.string() + ".tmp"));

  const io::H5Reader file(checkpoint);
  fields::Field<Scalar> resumed = fields::load_field<Scalar>(file);
  Trainer<Scalar> trainer(*setup.problem, resumed, setup.training);
  trainer.load_state(file);
  EXPECT_EQ(trainer.step(), 7);
  ASSERT_TRUE(trainer.run({}));
  EXPECT_EQ(trainer.step(), 20);
  ASSERT_EQ(resumed.parameters().size(), full.parameters().size());
  for (Eigen::Index i = 0; i < full.parameters().size(); ++i)
    ASSERT_EQ(resumed.parameters()(i), full.parameters()(i)) << "parameter " << i;
}

TEST(TrainerState, ResumedAdamRunIsBitExactDouble) { expect_resume_bit_exact<double>(); }
TEST(TrainerState, ResumedAdamRunIsBitExactFloat) { expect_resume_bit_exact<float>(); }

}  // namespace
}  // namespace nfield::solvers

namespace nfield::solvers {
namespace {

// An equation from outside the library: registered by name, then selected by `problem:`.
class OwnEquation final : public Problem {
 public:
  explicit OwnEquation(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {}
  const Domain& domain() const override { return domain_; }
  std::vector<LossTerm> loss_terms() const override {
    LossTerm fit;
    fit.name = "fit";
    fit.batch_key = "interior";
    fit.spec = autodiff::StreamSpec::values(domain_.input_dim());
    fit.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    fit.residual = [](const Eigen::MatrixXd& x) {
      return std::make_unique<LinearResidual>(std::vector<LinearResidual::Term>{{0, 0, 0, Eigen::VectorXd::Ones(1)}},
                                              x.col(0));
    };
    return {fit};
  }

 private:
  Domain domain_;
};

// A field that is NaN at one grid point has NaN errors, never the largest of its finite ones
// (std::max and Eigen's default maxCoeff drop a NaN).
TEST(GridError, ANonFiniteValueGivesNaNMetrics) {
  const RunSetup setup = load_run(write_config(kPoisson), {});
  const fields::Field<double> field(setup.field);
  const auto evaluate = [&](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x, bool poison) {
    autodiff::Streams<double> out;
    field.evaluate(layout, x, out);
    if (poison) out.data(x.rows() / 2, 0) = std::numeric_limits<double>::quiet_NaN();
    return out;
  };
  const GridMetrics clean = grid_error(*setup.problem,
                                       [&](const auto& l, const auto& x) { return evaluate(l, x, false); },
                                       setup.output);
  ASSERT_TRUE(clean.has_error);
  EXPECT_TRUE(std::isfinite(clean.rel_l2));
  EXPECT_GT(clean.max_abs_err, 0);
  const GridMetrics poisoned = grid_error(*setup.problem,
                                          [&](const auto& l, const auto& x) { return evaluate(l, x, true); },
                                          setup.output);
  EXPECT_TRUE(std::isnan(poisoned.rel_l2));
  EXPECT_TRUE(std::isnan(poisoned.max_abs_err));
}

TEST(ProblemRegistry, OutsideCodeRegistersAProblem) {
  register_problem("Own_Equation", [](const ProblemContext& c) { return std::make_unique<OwnEquation>(c); });
  EXPECT_THROW(register_problem("own_equation", make_poisson), std::logic_error);
  const auto config = testutil::write_config(
      "run_setup", "problem: OWN_EQUATION\n"
                   "domain: {lower: [0, 0], upper: [1, 1]}\n"
                   "field: {type: mlp, hidden: [8]}\n"
                   "training:\n  batch: {interior: 32}\n  stages: [{optimizer: adam, steps: 2}]\n");
  const RunSetup setup = load_run(config, {});
  ASSERT_EQ(setup.problem->loss_terms().size(), 1u);
  EXPECT_EQ(setup.problem->loss_terms()[0].name, "fit");
  const std::vector<std::string> names = problem_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "own_equation"), names.end());
}

}  // namespace
}  // namespace nfield::solvers
