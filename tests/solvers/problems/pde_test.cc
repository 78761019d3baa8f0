// SPDX-License-Identifier: MIT
//
// `problem: pde` (solvers/problems/pde.cc): derivative symbols read from the planned streams
// against closed forms (sums of exponentials, every order and kind up to 4) and against finite
// differences of a real field, the expression residual's adjoint against central differences,
// the same first loss and gradient as the built-in Poisson, located config errors, and a
// short run whose error falls.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "fields/field.h"
#include "solvers/problems/burgers_reference.h"
#include "solvers/problems/pde_residual.h"
#include "solvers/problems/pde_streams.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/exponential_streams.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

using testutil::Exponentials;
using testutil::exponential_streams;
using testutil::random_exponentials;

using Kind = DerivativeSymbol::Kind;

// The symbol's closed form for the exponentials.
double exact_symbol(const DerivativeSymbol& s, const Exponentials& f, const Eigen::VectorXd& x, int space_dim) {
  return f.sum(s.output, x, [&](const Eigen::VectorXd& r) {
    const double lap = r.head(space_dim).squaredNorm();
    if (s.kind == Kind::kLaplacian) return lap;
    if (s.kind == Kind::kBilaplacian) return lap * lap;
    double product = 1;
    for (int a : s.axes) product *= r(a);
    return product;
  });
}

double symbol_value(const std::vector<SymbolTerm>& terms, const autodiff::Streams<double>& s, Eigen::Index n) {
  double v = 0;
  for (const SymbolTerm& t : terms) v += t.coefficient * s.stream(t.stream)(n, t.channel);
  return v;
}

std::vector<DerivativeSymbol> parse_all(const std::vector<std::string>& names, const std::vector<std::string>& inputs,
                                        int space_dim) {
  std::vector<DerivativeSymbol> out;
  for (const std::string& name : names) {
    const auto s = parse_derivative_symbol(name, {"u", "v"}, inputs, space_dim);
    EXPECT_TRUE(s.has_value()) << name;
    if (s) out.push_back(*s);
  }
  return out;
}

struct PlanCase {
  std::vector<std::string> inputs;
  int space_dim;
  std::vector<std::string> symbols;
};

TEST(PdeStreams, EverySymbolMatchesClosedForms) {
  const PlanCase cases[] = {
      {{"x"}, 1, {"u", "u_x", "u_xx", "lap(u)", "u_xxx", "u_xxxx", "bilap(v)", "v_x"}},
      {{"x", "t"}, 1, {"u", "u_t", "u_x", "u_tt", "u_xt", "u_xx", "u_xxt", "u_xxxx", "v_ttx", "u_xtxt"}},
      {{"x", "y"}, 2, {"lap(u)", "bilap(u)", "u_xxyy", "u_xyyy", "v_xy", "u_xxy", "v_yyyy"}},
      {{"x", "y", "z", "t"}, 3, {"lap(v)", "bilap(u)", "u_xyzt", "u_xyz", "u_tttt", "v_zt", "u_y"}},
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  for (const PlanCase& c : cases) {
    SCOPED_TRACE(c.symbols.front() + " … in " + std::to_string(c.inputs.size()) + " inputs");
    const int d = static_cast<int>(c.inputs.size());
    const std::vector<DerivativeSymbol> symbols = parse_all(c.symbols, c.inputs, c.space_dim);
    const StreamPlan plan = plan_streams(symbols, d, c.space_dim);
    const autodiff::StreamLayout layout(plan.spec);
    const Exponentials f = random_exponentials(d, 2, rng);
    const Eigen::MatrixXd x = Eigen::MatrixXd::NullaryExpr(5, d, [&] { return coordinate(rng); });
    const autodiff::Streams<double> s = exponential_streams(layout, f, x, 2);
    for (std::size_t k = 0; k < symbols.size(); ++k)
      for (Eigen::Index n = 0; n < x.rows(); ++n) {
        const double want = exact_symbol(symbols[k], f, x.row(n).transpose(), c.space_dim);
        EXPECT_NEAR(symbol_value(plan.symbols[k], s, n), want, 1e-12 * std::max(1.0, std::abs(want))) << c.symbols[k];
      }
  }
}

TEST(PdeStreams, LaplacianCostsOneOperatorStream) {
  const auto symbols = parse_all({"lap(u)", "lap(v)", "u_xx", "v_xx"}, {"x", "y", "t"}, 2);
  const StreamPlan plan = plan_streams(symbols, 3, 2);
  const autodiff::StreamLayout layout(plan.spec);
  const autodiff::StreamLayout poisson(autodiff::StreamSpec::laplacian(2));
  EXPECT_EQ(layout.tangents(), 2);   // x, y: no tangent along t
  EXPECT_EQ(layout.operators(), 2);  // Δ (both outputs) and ∂xx (both outputs)
  EXPECT_EQ(layout.taylor_dirs(), 0);
  const StreamPlan lap = plan_streams(parse_all({"lap(u)"}, {"x", "y"}, 2), 2, 2);
  EXPECT_EQ(lap.spec.tangents, poisson.spec().tangents);
  ASSERT_EQ(lap.spec.operators.size(), 1u);
  EXPECT_EQ(lap.spec.operators[0], poisson.spec().operators[0]);
  // u_xxyy shares directions with u_xxxx and u_yyyy: e_x, e_y, e_x+e_y, 2e_x+e_y, e_x+2e_y.
  const StreamPlan fourth = plan_streams(parse_all({"u_xxxx", "u_xxyy", "u_yyyy"}, {"x", "y"}, 2), 2, 2);
  EXPECT_EQ(fourth.spec.taylor_directions.cols(), 5);
  EXPECT_EQ(fourth.spec.taylor_order, 4);
}

TEST(PdeStreams, SymbolErrors) {
  const std::vector<std::string> outputs{"u", "v"}, inputs{"x", "t"};
  EXPECT_FALSE(parse_derivative_symbol("u_xq", outputs, inputs, 1).has_value());
  EXPECT_FALSE(parse_derivative_symbol("w_x", outputs, inputs, 1).has_value());
  EXPECT_FALSE(parse_derivative_symbol("u_", outputs, inputs, 1).has_value());
  auto reason = [&](const std::string& name) {
    try {
      parse_derivative_symbol(name, outputs, inputs, 1);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(reason("u_xy"), "u_xy: the domain has no variable 'y' (variables: x, t)");
  EXPECT_EQ(reason("u_xxxxt"), "u_xxxxt: derivatives go up to order 4, this one is of order 5");
  EXPECT_EQ(reason("lap(w)"), "lap(w): 'w' is no output (outputs: u, v)");
}

// The symbols from a real network's streams against finite differences of its values: the
// plan's reading of the stream conventions (tangents, operators, Taylor coefficients).
TEST(PdeStreams, SymbolsOfAFieldMatchFiniteDifferences) {
  fields::FieldOptions options;
  options.input_dim = 2;
  options.output_dim = 1;
  options.hidden = {16, 16};
  options.first_omega = 1;
  options.hidden_omega = 1;
  options.seed = 3;
  fields::Field<double> field(options);
  const std::vector<std::string> names{"u_x", "u_xy", "u_yy", "u_xxy", "u_xxyy", "bilap(u)"};
  const auto symbols = parse_all(names, {"x", "y"}, 2);
  const StreamPlan plan = plan_streams(symbols, 2, 2);
  const autodiff::StreamLayout layout(plan.spec);
  Eigen::MatrixXd x(1, 2);
  x << 0.3, -0.2;
  autodiff::Streams<double> s;
  field.evaluate(layout, x, s);
  // Central differences of u(x + i h e_x + j h e_y) by the stencil's weights per axis.
  const double h = 2e-2;
  auto u = [&](double dx, double dy) {
    Eigen::MatrixXd p = x;
    p(0, 0) += dx;
    p(0, 1) += dy;
    return field.values(p)(0, 0);
  };
  const std::vector<std::vector<double>> stencil = {
      {0, 0, 1, 0, 0}, {1 / 12.0, -8 / 12.0, 0, 8 / 12.0, -1 / 12.0}, {-1 / 12.0, 16 / 12.0, -30 / 12.0, 16 / 12.0, -1 / 12.0},
      {-0.5, 1, 0, -1, 0.5}, {1, -4, 6, -4, 1}};
  auto difference = [&](int ox, int oy) {
    double sum = 0;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        sum += stencil[ox][i] * stencil[oy][j] * u((i - 2) * h, (j - 2) * h);
    return sum / std::pow(h, ox + oy);
  };
  const double want[] = {difference(1, 0), difference(1, 1), difference(0, 2), difference(2, 1), difference(2, 2),
                         difference(4, 0) + 2 * difference(2, 2) + difference(0, 4)};
  for (std::size_t k = 0; k < names.size(); ++k) {
    const double got = symbol_value(plan.symbols[k], s, 0);
    EXPECT_NEAR(got, want[k], 2e-3 * std::max(1.0, std::abs(want[k]))) << names[k];
  }
}

// backward against central differences of evaluate, over every stream entry a residual reads,
// for reads that take each Jet size (1, 4, 16, 32).
TEST(ExpressionResidual, AdjointMatchesCentralDifferences) {
  const std::vector<std::string> inputs{"x", "y", "t"};
  const std::vector<std::vector<std::string>> reads = {
      {"u_t"},
      {"u_t", "u", "u_x", "lap(u)"},
      {"u", "v", "u_x", "u_y", "v_t", "u_xx", "u_xy", "v_tt", "lap(v)", "u_xxx", "u_xxyy", "bilap(v)", "v_xyt"},
      {"u", "v", "u_x", "u_y", "u_t", "v_x", "v_y", "v_t", "u_xx", "u_xy", "u_yy", "u_xt", "u_yt", "u_tt", "v_xx",
       "v_xy", "v_yy", "u_xxx", "u_yyy", "u_xxy"},
  };
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (const auto& names : reads) {
    SCOPED_TRACE(std::to_string(names.size()) + " reads");
    const auto symbols = parse_all(names, inputs, 2);
    const StreamPlan plan = plan_streams(symbols, 3, 2);
    const autodiff::StreamLayout layout(plan.spec);
    io::ExpressionScope scope;
    scope.slots = {{"x", 0}, {"y", 1}, {"t", 2}};
    std::string text = "sin(x) * " + names[0];
    for (std::size_t k = 0; k < names.size(); ++k) {
      scope.slots.emplace_back(names[k], 3 + static_cast<int>(k));
      if (k > 0) text += (k % 3 == 0 ? " + tanh(" : k % 3 == 1 ? " - t*exp(0.3*" : " + ") + names[k] + (k % 3 == 2 ? "^2" : ")") + " * " + names[k - 1];
    }
    const auto expression = std::make_shared<const io::CompiledExpression>(text, scope);
    const Eigen::MatrixXd x = Eigen::MatrixXd::NullaryExpr(7, 3, [&] { return uniform(rng); });
    const ExpressionResidual residual(expression, std::make_shared<const std::vector<std::vector<SymbolTerm>>>(plan.symbols), x);
    autodiff::Streams<double> out, adjoint;
    out.resize(4, layout.count(), 2);
    out.data = Eigen::MatrixXd::NullaryExpr(out.data.rows(), 2, [&] { return uniform(rng); });
    adjoint.resize(4, layout.count(), 2);
    adjoint.data.setZero();
    const Eigen::MatrixXd r_bar = Eigen::MatrixXd::NullaryExpr(4, 1, [&] { return uniform(rng); });
    residual.backward(2, layout, out, r_bar, adjoint);  // points 2 … 5 of x
    for (Eigen::Index i = 0; i < out.data.rows(); ++i)
      for (Eigen::Index c = 0; c < 2; ++c) {
        const double h = 1e-6, saved = out.data(i, c);
        Eigen::MatrixXd up, down;
        out.data(i, c) = saved + h;
        residual.evaluate(2, layout, out, up);
        out.data(i, c) = saved - h;
        residual.evaluate(2, layout, out, down);
        out.data(i, c) = saved;
        const double want = r_bar.col(0).dot(up.col(0) - down.col(0)) / (2 * h);
        // Truncation, plus the rounding of r in the difference (polarized symbols reach
        // 64/3 times a stream entry, and r their squares).
        const double rounding = 4 * std::numeric_limits<double>::epsilon() * up.cwiseAbs().maxCoeff() / h;
        EXPECT_NEAR(adjoint.data(i, c), want, 1e-7 * std::max(1.0, std::abs(want)) + rounding) << "entry " << i << ", " << c;
      }
  }
}

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  return testutil::write_config("pde", text, name);
}

// The built-in Poisson and its `problem: pde` restatement: the same streams, points and
// residual, so the same first loss and gradient on the same network.
TEST(Pde, PoissonRestatementGivesTheBuiltInFirstLoss) {
  const std::filesystem::path configs = std::filesystem::path(NFIELD_SOURCE_DIR) / "configs";
  const std::vector<std::string> threads{"training.threads=1"};
  RunSetup builtin = load_run(configs / "poisson_2d.yaml", threads);
  RunSetup pde = load_run(configs / "poisson_2d_pde.yaml", threads);
  fields::Field<double> field_a(builtin.field), field_b(pde.field);
  ASSERT_EQ(field_a.parameters(), field_b.parameters());
  Trainer<double> a(*builtin.problem, field_a, builtin.training), b(*pde.problem, field_b, pde.training);
  Eigen::VectorXd ga(field_a.parameter_count()), gb(field_b.parameter_count());
  const double la = a.loss_and_gradient_at(field_a.parameters().data(), ga.data());
  const double lb = b.loss_and_gradient_at(field_b.parameters().data(), gb.data());
  std::printf("first loss: poisson %.17g, pde %.17g; gradient difference %.3g of %.3g\n", la, lb, (ga - gb).norm(), ga.norm());
  EXPECT_EQ(a.points(0), b.points(0));
  EXPECT_EQ(a.points(1), b.points(1));
  EXPECT_NEAR(lb, la, 1e-12 * la);
  EXPECT_LT((ga - gb).norm(), 1e-10 * ga.norm());
  EXPECT_EQ(a.term_names(), b.term_names());
}

// rel. L2 error of the field against the problem's exact solution on a 33 × 33 grid.
double grid_error(const Problem& problem, const fields::Field<double>& field) {
  Eigen::MatrixXd x(33 * 33, 2);
  for (int i = 0; i < 33; ++i)
    for (int j = 0; j < 33; ++j) x.row(i * 33 + j) << i / 32.0, j / 32.0;
  const Eigen::MatrixXd exact = problem.exact(x);
  return (field.values(x) - exact).norm() / exact.norm();
}

TEST(Pde, ShortPoissonRunLowersTheError) {
  const std::filesystem::path config = std::filesystem::path(NFIELD_SOURCE_DIR) / "configs" / "poisson_2d_pde.yaml";
  RunSetup setup = load_run(config, {"training.threads=1", "training.batch={interior: 256, boundary: 64}",
                                     "training.stages=[{optimizer: adam, steps: 300, lr: 5.0e-3, schedule: cosine, lr_final: 1.0e-4}]"});
  ASSERT_TRUE(setup.problem->has_exact());
  fields::Field<double> field(setup.field);
  const double before = grid_error(*setup.problem, field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  const double after = grid_error(*setup.problem, field);
  std::printf("poisson_2d_pde, 300 Adam steps: rel_l2 %.3e -> %.3e\n", before, after);
  EXPECT_LT(after, before / 10);  // measured: 2.1 -> 0.11 (seed 0, one thread)
}

// u_xx + u_yy costs one Laplacian stream (as lap(u)); u_xx - u_yy two operator streams.
TEST(Pde, SumOfSecondDerivativesIsOneLaplacianStream) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  residuals: ["u_xx + u_yy - x", "u_xx - u_yy"]
)yaml";
  const RunSetup setup = load_run(write_config("sum", text), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 2u);
  EXPECT_EQ(terms[0].spec.operators.size(), 1u);
  EXPECT_EQ(terms[1].spec.operators.size(), 1u);  // folded: tr(diag(1, −1) ∇²u)
  std::mt19937 rng(2);
  const Exponentials f = random_exponentials(2, 1, rng);
  Random points(3);
  const Eigen::MatrixXd x = terms[0].sample(points, 9);
  for (const LossTerm& term : terms) {
    const autodiff::StreamLayout layout(term.spec);
    const autodiff::Streams<double> s = exponential_streams(layout, f, x, 1);
    Eigen::MatrixXd r;
    term.residual(x)->evaluate(0, layout, s, r);
    for (Eigen::Index n = 0; n < x.rows(); ++n) {
      const Eigen::VectorXd p = x.row(n).transpose();
      const double want = &term == &terms[0]
          ? f.sum(0, p, [](const Eigen::VectorXd& c) { return c.squaredNorm(); }) - p(0)
          : f.sum(0, p, [](const Eigen::VectorXd& c) { return c(0) * c(0) - c(1) * c(1); });
      EXPECT_NEAR(r(n, 0), want, 1e-12) << term.name;
    }
  }
}

// Second derivatives of one output with constant coefficients become one weighted operator
// stream (the built-in wave's); a varying coefficient, a symbol read twice or two outputs
// keep theirs. Every form still has the value of the expression as written.
TEST(Pde, ConstantCoefficientSecondDerivativesFoldIntoOneStream) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1], time: [0, 1]}
outputs: [u, v]
constants: {c: 1.5}
equation:
  residuals: ["u_tt - c^2*(u_xx + u_yy)", "-(2*u_tt) + u_xy/4 - 3*u_yy + sin(x)", "u_tt - x*u_xx",
              "u_tt - u_xx + u_xx*u", "u_tt - v_xx", "-u_xx - u_yy + u_t"]
)yaml";
  const RunSetup setup = load_run(write_config("fold", text), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 6u);
  const std::vector<std::size_t> streams = {1, 1, 2, 2, 2, 1};
  using V = Eigen::VectorXd;
  const auto d2 = [](int a, int b) { return [a, b](const V& c) { return c(a) * c(b); }; };
  std::mt19937 rng(4);
  const Exponentials f = random_exponentials(3, 2, rng);
  Random points(5);
  const Eigen::MatrixXd x = terms[0].sample(points, 7);
  for (std::size_t k = 0; k < terms.size(); ++k) {
    EXPECT_EQ(terms[k].spec.operators.size(), streams[k]) << terms[k].name;
    const autodiff::StreamLayout layout(terms[k].spec);
    const autodiff::Streams<double> s = exponential_streams(layout, f, x, 2);
    Eigen::MatrixXd r;
    terms[k].residual(x)->evaluate(0, layout, s, r);
    for (Eigen::Index n = 0; n < x.rows(); ++n) {
      const V p = x.row(n).transpose();
      const auto u = [&](auto g) { return f.sum(0, p, g); };
      const double tt = u(d2(2, 2)), xx = u(d2(0, 0)), yy = u(d2(1, 1)), value = u([](const V&) { return 1.0; });
      const double want[] = {tt - 2.25 * (xx + yy), -2 * tt + u(d2(0, 1)) / 4 - 3 * yy + std::sin(p(0)),
                             tt - p(0) * xx, tt - xx + xx * value, tt - f.sum(1, p, d2(0, 0)),
                             -xx - yy + u([](const V& c) { return c(2); })};
      EXPECT_NEAR(r(n, 0), want[k], 1e-12 * (1 + std::abs(want[k]))) << terms[k].name;
    }
  }
}

// A fourth- and mixed third-order residual from a config vanishes on its exact solution
// u = exp(ax + by): bilap(u) = (a² + b²)² u, u_xxy = a²b u.
TEST(Pde, HigherOrderResidualVanishesOnItsSolution) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
constants: {a: 0.5, b: -0.3, c: "(a^2 + b^2)^2 + a^2*b"}
equation:
  residuals: ["bilap(u) + u_xxy - c*exp(a*x + b*y)"]
)yaml";
  const RunSetup setup = load_run(write_config("fourth", text), {});
  const LossTerm term = setup.problem->loss_terms()[0];
  EXPECT_EQ(term.spec.taylor_order, 4);
  Exponentials f;
  f.rates = {Eigen::Vector2d(0.5, -0.3)};
  f.weights = Eigen::MatrixXd::Ones(1, 1);
  Random points(4);
  const Eigen::MatrixXd x = term.sample(points, 17);
  const autodiff::StreamLayout layout(term.spec);
  Eigen::MatrixXd r;
  term.residual(x)->evaluate(0, layout, exponential_streams(layout, f, x, 1), r);
  EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-13);
  f.rates[0](1) = -0.31;  // another solution's streams: the residual sees it
  term.residual(x)->evaluate(0, layout, exponential_streams(layout, f, x, 1), r);
  EXPECT_GT(r.cwiseAbs().maxCoeff(), 1e-3);
}

// A simply supported beam, u_xxxx = π⁴ sin(πx), u = u_xx = 0 at both ends (boundary
// residuals): Taylor streams of order 4 in training, and residuals on faces.
TEST(Pde, BeamWithBoundaryResidualsTrains) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0], upper: [1]}
equation:
  residuals:
    - "u_xxxx - pi^4*sin(pi*x)"
    - {expr: "u", on: boundary, weight: 100}
    - {expr: "u_xx", on: boundary, name: moment}
reference:
  exact: "sin(pi*x)"
field: {type: siren, hidden: [32, 32], first_omega: 2, hidden_omega: 1}
training:
  seed: 0
  threads: 1
  precision: double
  batch: {interior: 256, boundary: 32}
  stages:
    - {optimizer: adam, steps: 500, lr: 2.0e-3, schedule: cosine, lr_final: 1.0e-4}
    - {optimizer: lbfgs, steps: 100}
)yaml";
  RunSetup setup = load_run(write_config("beam", text), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 3u);
  EXPECT_EQ(terms[1].name, "residual_1");
  EXPECT_EQ(terms[1].batch_key, "boundary");
  EXPECT_EQ(terms[2].name, "moment");
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  const Eigen::MatrixXd x = Eigen::VectorXd::LinSpaced(101, 0, 1);
  const Eigen::MatrixXd exact = setup.problem->exact(x);
  const double rel_l2 = (field.values(x) - exact).norm() / exact.norm();
  std::printf("beam, 500 Adam + 100 L-BFGS steps: rel_l2 %.3e\n", rel_l2);
  EXPECT_LT(rel_l2, 2e-3);  // measured 2.8e-4 (nfield run, the same config)
}

// A residual `on: initial` draws its points at t0 from the `initial` batch; without a time
// interval it is a located error.
TEST(Pde, InitialResidual) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0], upper: [1], time: [0.5, 1]}
equation:
  residuals:
    - "u_t - u_xx"
    - {expr: "u_t", on: initial}
)yaml";
  const RunSetup setup = load_run(write_config("initial", text), {});
  const LossTerm term = setup.problem->loss_terms()[1];
  EXPECT_EQ(term.name, "residual_1");
  EXPECT_EQ(term.batch_key, "initial");
  Random rng(1);
  const Eigen::MatrixXd x = term.sample(rng, 8);
  EXPECT_TRUE((x.col(1).array() == 0.5).all());
  std::string no_time = text;
  no_time.replace(no_time.find(", time: [0.5, 1]"), 16, "");
  no_time.replace(no_time.find("u_t - u_xx"), 10, "u_xx");
  testutil::expect_located_error(write_config("initial_no_time", no_time),
                                 {6, 25, "equation.residuals[1].on", "'initial' needs a domain with a time interval"});
}

// The constants reach the conditions' values, soft and hard; one read only there is used.
TEST(Pde, ConstantsInConditions) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0], upper: [1], time: [0, 1]}
constants: {a: 3, amplitude: "2*a"}
equation:
  residuals: ["u_t - u_xx"]
conditions:
  - {on: [x_max], type: dirichlet, value: "a*t"}
  - {on: initial, type: value, value: "amplitude*sin(pi*x)", enforce: hard}
)yaml";
  const RunSetup setup = load_run(write_config("constants_in_conditions", text), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 2u);
  ASSERT_EQ(terms[1].name, "dirichlet");
  Random rng(5);
  const Eigen::MatrixXd x = terms[1].sample(rng, 6);
  const autodiff::StreamLayout layout(terms[1].spec);
  autodiff::Streams<double> zero;
  zero.resize(x.rows(), layout.count(), 1);
  zero.data.setZero();
  Eigen::MatrixXd r;
  terms[1].residual(x)->evaluate(0, layout, zero, r);
  EXPECT_TRUE(r.col(0).isApprox(-3 * x.col(1), 1e-14));  // u − g with u = 0, g = a t
  ASSERT_NE(setup.problem->ansatz(), nullptr);
}

// reference.solution: burgers_sine gives the error metrics against the Cole–Hopf solution at
// the config's ν; it needs one output over x and t.
TEST(Pde, BurgersReferenceSolution) {
  const char* text = R"yaml(problem: pde
domain: {lower: [-1], upper: [1], time: [0, 1]}
constants: {nu: "0.01/pi"}
equation:
  residuals: ["u_t + u*u_x - nu*u_xx"]
reference: {solution: burgers_sine, nu: nu}
)yaml";
  const RunSetup setup = load_run(write_config("burgers_reference", text), {});
  ASSERT_TRUE(setup.problem->has_exact());
  Eigen::MatrixXd x(3, 2);
  x << -0.5, 0.0, 0.3, 0.5, 0.01, 1.0;
  const Eigen::MatrixXd u = setup.problem->exact(x);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    EXPECT_EQ(u(i, 0), burgers_sine_solution(x(i, 0), x(i, 1), {.nu = 0.01 / std::numbers::pi}));
  EXPECT_DOUBLE_EQ(u(0, 0), std::sin(std::numbers::pi * 0.5));
  std::string two_d = text;
  two_d.replace(two_d.find("{lower: [-1], upper: [1]"), 24, "{lower: [-1, 0], upper: [1, 1]");
  testutil::expect_located_error(write_config("burgers_reference_2d", two_d),
                                 {6, 23, "reference.solution", "burgers_sine needs one output over one space variable"});
  std::string other = text;
  other.replace(other.find("burgers_sine"), 12, "burgers_cos");
  testutil::expect_located_error(write_config("burgers_reference_name", other),
                                 {6, 23, "reference.solution", "burgers_sine"});
}

const char* kTwoOutputs = R"yaml(problem: pde
domain: {lower: [0], upper: [1], time: [0, 1]}
outputs: [u, v]
constants: {nu: "0.01/pi", two_nu: 2*nu}
equation:
  residuals:
    - "u_t - nu*u_xx + v"
    - "v_t + u_xq"
)yaml";

// An interior residual with `where` draws its points in that region only, and a region no
// point of the domain lies in is refused at its key.
TEST(Pde, InteriorResidualInARegion) {
  const char* text = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  residuals:
    - "lap(u) - 1"
    - {expr: "lap(u) - 1", where: "(x - 0.3)^2 + (y - 0.6)^2 < 0.01", batch: near, name: near}
training: {batch: {interior: 100, near: 50}}
)yaml";
  const RunSetup setup = load_run(write_config("region", text), {});
  for (const LossTerm& term : setup.problem->loss_terms()) {
    if (term.name != "near") continue;
    EXPECT_EQ(term.batch_key, "near");
    Random rng(3);
    const Eigen::MatrixXd x = term.sample(rng, 500);
    ASSERT_EQ(x.rows(), 500);
    for (Eigen::Index r = 0; r < x.rows(); ++r) ASSERT_LT(std::hypot(x(r, 0) - 0.3, x(r, 1) - 0.6), 0.1);
    // Uniform over the disk: the mean radius² is r²/2 (4 standard errors of 500 draws).
    const double mean_r2 = ((x.col(0).array() - 0.3).square() + (x.col(1).array() - 0.6).square()).mean();
    EXPECT_NEAR(mean_r2, 0.005, 4 * 0.01 / std::sqrt(12.0 * 500));
  }
  std::string empty = text;
  empty.replace(empty.find("< 0.01"), 6, "< 0");
  testutil::expect_located_error(write_config("empty_region", empty),
                                 {6, 35, "equation.residuals[1].where", "no point of 2^14 drawn in the domain lies in this region"});
}

TEST(Pde, ConfigErrorsAreLocated) {
  using testutil::expect_located_error;
  expect_located_error(write_config("unknown_symbol", kTwoOutputs),
                       {8, 14, "equation.residuals[1]", "unknown symbol 'u_xq' (outputs: u, v; variables: x, t; constants: nu, two_nu)"});
  std::string text = kTwoOutputs;
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  expect_located_error(write_config("no_variable", with("u_xq", "u_xy")),
                       {8, 14, "equation.residuals[1]", "u_xy: the domain has no variable 'y' (variables: x, t)"});
  expect_located_error(write_config("order", with("u_xq", "u_xxtxx")),
                       {8, 14, "equation.residuals[1]", "derivatives go up to order 4"});
  expect_located_error(write_config("no_output", with("\"v_t + u_xq\"", "{expr: \"sin(pi*x) - nu\", weight: 2}")),
                       {8, 14, "equation.residuals[1].expr", "reads no output (outputs: u, v)"});
  expect_located_error(write_config("bad_constant", with("2*nu", "2*mu")),
                       {4, 38, "constants.two_nu", "unknown symbol 'mu' (constants before this one: nu"});
  expect_located_error(write_config("constant_name", with("two_nu:", "u_x:")),
                       {4, 33, "constants.u_x", "reads as an output or its derivative"});
  expect_located_error(write_config("output_name", with("[u, v]", "[u, x]")),
                       {3, 10, "outputs", "output name 'x' is taken"});
  expect_located_error(write_config("reference", with("u_xq", "u_x") + "reference: {exact: {u: \"x\", w: \"t\"}}\n"),
                       {9, 32, "reference.exact.w", "'w' is no output (outputs: u, v)"});
  expect_located_error(write_config("unused_constant", with("u_xq", "u_x")),
                       {4, 36, "constants.two_nu", "constant 'two_nu' is never used"});
  expect_located_error(write_config("unknown_function", with("u_xq", "grad(u)")),
                       {8, 14, "equation.residuals[1]", "unknown function 'grad'"});
  expect_located_error(write_config("hard_taylor", with("u_xq", "u_xxx") +
                                                       "conditions:\n  - {on: boundary, type: dirichlet, value: [\"0\", \"0\"], enforce: hard}\n"),
                       {8, 7, "equation.residuals[1]", "order above 2"});
}

}  // namespace
}  // namespace nfield::solvers
