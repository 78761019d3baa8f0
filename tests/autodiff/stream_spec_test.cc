// SPDX-License-Identifier: MIT
//
// StreamSpec validation (errors name the field), StreamLayout's indices, operator terms and
// forward orders, input seeding, and the argument checks of elementwise rules and
// Sequential.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "autodiff/elementwise.h"
#include "autodiff/sequential.h"
#include "autodiff/streams.h"
#include "fields/dense.h"

namespace nfield::autodiff {
namespace {

// Runs f, expects std::invalid_argument whose message contains every one of `parts`.
template <typename F>
void expect_invalid(F&& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one mentioning " << *parts.begin();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    for (const std::string& part : parts)
      EXPECT_NE(what.find(part), std::string::npos) << "'" << what << "' lacks '" << part << "'";
  }
}

TEST(StreamSpec, RejectsNonSymmetricOperator) {
  StreamSpec s = StreamSpec::gradient(2);
  Eigen::MatrixXd c(2, 2);
  c << 1, 2, 0, 1;
  s.add_operator(Eigen::MatrixXd::Identity(2, 2));
  s.add_operator(c);
  expect_invalid([&] { s.validate(); }, {"StreamSpec.operators[1]", "symmetric"});
  expect_invalid([&] { StreamLayout layout(s); }, {"StreamSpec.operators[1]", "symmetric"});
}

TEST(StreamSpec, AcceptsSymmetricOperatorUpToRounding) {
  StreamSpec s = StreamSpec::gradient(2);
  Eigen::MatrixXd c(2, 2);
  c << 1, 0.1 + 1e-17, 0.1, -3;
  s.add_operator(c);
  EXPECT_NO_THROW(s.validate());
}

TEST(StreamSpec, RejectsWrongShapes) {
  {
    StreamSpec s = StreamSpec::gradient(3);
    s.add_operator(Eigen::MatrixXd::Identity(2, 2));
    expect_invalid([&] { s.validate(); }, {"StreamSpec.operators[0]", "2x2", "T = 3"});
  }
  {
    StreamSpec s = StreamSpec::gradient(2);
    s.add_operator(Eigen::MatrixXd::Identity(2, 3));
    expect_invalid([&] { s.validate(); }, {"StreamSpec.operators[0]", "2x3"});
  }
  {
    StreamSpec s = StreamSpec::values(3);
    s.tangents = Eigen::MatrixXd::Identity(2, 2);
    expect_invalid([&] { s.validate(); }, {"StreamSpec.tangents", "2x2", "input_dim = 3"});
  }
  {
    StreamSpec s = StreamSpec::values(2);
    s.set_taylor(Eigen::MatrixXd::Ones(3, 1), 2);
    expect_invalid([&] { s.validate(); }, {"StreamSpec.taylor_directions", "3x1"});
  }
  {
    StreamSpec s = StreamSpec::values(2);
    s.set_taylor(Eigen::MatrixXd::Ones(2, 1), 0);
    expect_invalid([&] { s.validate(); }, {"StreamSpec.taylor_order", "0"});
  }
  {
    StreamSpec s = StreamSpec::values(2);
    s.taylor_order = -1;
    expect_invalid([&] { s.validate(); }, {"StreamSpec.taylor_order", "-1"});
  }
  {
    StreamSpec s;
    expect_invalid([&] { s.validate(); }, {"StreamSpec.input_dim", "0"});
  }
  {
    // An operator needs tangents to act on.
    StreamSpec s = StreamSpec::values(2);
    s.add_operator(Eigen::MatrixXd::Identity(2, 2));
    expect_invalid([&] { s.validate(); }, {"StreamSpec.operators[0]", "T = 0"});
  }
}

TEST(StreamLayout, IndicesAndCounts) {
  StreamSpec s = StreamSpec::laplacian(3);
  s.add_operator(Eigen::MatrixXd::Identity(3, 3));
  s.set_taylor(Eigen::MatrixXd::Ones(3, 2), 4);
  const StreamLayout l(s);
  EXPECT_EQ(l.count(), 1 + 3 + 2 + 2 * 4);
  EXPECT_EQ(l.value(), 0);
  EXPECT_EQ(l.tangent(2), 3);
  EXPECT_EQ(l.op(1), 5);
  EXPECT_EQ(l.taylor(0, 1), 6);
  EXPECT_EQ(l.taylor(1, 4), 13);
  EXPECT_EQ(StreamLayout(StreamSpec::values(2)).count(), 1);
  // A default-constructed spec with only input_dim set is values only.
  StreamSpec bare;
  bare.input_dim = 2;
  EXPECT_EQ(StreamLayout(bare).count(), 1);
}

TEST(StreamLayout, ForwardOrder) {
  EXPECT_EQ(StreamLayout(StreamSpec::values(2)).forward_order(), 0);
  EXPECT_EQ(StreamLayout(StreamSpec::gradient(2)).forward_order(), 1);
  EXPECT_EQ(StreamLayout(StreamSpec::laplacian(2)).forward_order(), 2);
  StreamSpec t = StreamSpec::values(2);
  t.set_taylor(Eigen::MatrixXd::Ones(2, 1), 1);
  EXPECT_EQ(StreamLayout(t).forward_order(), 1);
  t.set_taylor(Eigen::MatrixXd::Ones(2, 1), 4);
  EXPECT_EQ(StreamLayout(t).forward_order(), 4);
  StreamSpec lt = StreamSpec::laplacian(2);
  lt.set_taylor(Eigen::MatrixXd::Ones(2, 1), 1);
  EXPECT_EQ(StreamLayout(lt).forward_order(), 2);
}

TEST(StreamLayout, OperatorTermsVisitEachPairOnce) {
  StreamSpec s = StreamSpec::gradient(3);
  Eigen::MatrixXd c(3, 3);
  c << 1, 2, 0,  //
      2, 0, -1,  //
      0, -1, 5;
  s.add_operator(c);
  const StreamLayout l(s);
  const auto& terms = l.terms(0);
  ASSERT_EQ(terms.size(), 4u);  // (0,0), (0,1), (1,2), (2,2); zeros skipped
  double total = 0;
  for (const OperatorTerm& t : terms) {
    EXPECT_LE(t.i, t.j);
    EXPECT_EQ(t.coefficient, t.i == t.j ? c(t.i, t.i) : c(t.i, t.j) + c(t.j, t.i));
    total += t.coefficient;
  }
  EXPECT_EQ(total, c.sum());
}

TEST(SeedInputStreams, SeedsValueTangentsOperatorsAndTaylor) {
  StreamSpec s = StreamSpec::values(2);
  s.tangents = (Eigen::MatrixXd(2, 3) << 1, 2, 3, 4, 5, 6).finished();
  s.add_operator(Eigen::MatrixXd::Identity(3, 3));
  s.set_taylor((Eigen::MatrixXd(2, 1) << 7, 8).finished(), 3);
  const StreamLayout l(s);
  const Eigen::MatrixXd x = (Eigen::MatrixXd(2, 2) << 0.5, -1, 2, 3).finished();
  Streams<double> in;
  seed_input_streams<double>(l, x, in);
  ASSERT_EQ(in.count, l.count());
  EXPECT_EQ(in.stream(0), x);
  for (int t = 0; t < 3; ++t)
    for (int n = 0; n < 2; ++n) EXPECT_EQ(in.stream(l.tangent(t)).row(n), s.tangents.col(t).transpose());
  EXPECT_TRUE(in.stream(l.op(0)).isZero(0));
  EXPECT_EQ(in.stream(l.taylor(0, 1)).row(1), Eigen::RowVector2d(7, 8));
  EXPECT_TRUE(in.stream(l.taylor(0, 2)).isZero(0));
  EXPECT_TRUE(in.stream(l.taylor(0, 3)).isZero(0));
  const Eigen::MatrixXd wrong = Eigen::MatrixXd::Zero(2, 3);
  expect_invalid([&] { seed_input_streams<double>(l, wrong, in); }, {"3 columns", "expects 2"});
}

TEST(Elementwise, RefusesTooFewDerivativeTables) {
  const StreamLayout l(StreamSpec::laplacian(2));
  Streams<double> z, y, y_bar, z_bar;
  z.resize(2, l.count(), 3);
  z.data.setOnes();
  y_bar = z;
  std::vector<Matrix<double>> tables(2, Matrix<double>::Ones(2, 3));
  EXPECT_THROW(elementwise_forward(l, tables, z, y), std::logic_error);
  tables.resize(3, Matrix<double>::Ones(2, 3));
  EXPECT_NO_THROW(elementwise_forward(l, tables, z, y));
  EXPECT_THROW(elementwise_backward(l, tables, z, y_bar, z_bar), std::logic_error);
}

TEST(Sequential, RejectsBadOptionsAndWidths) {
  expect_invalid([] { Sequential<double> s({.block_points = 0}); },
                 {"SequentialOptions.block_points", "0"});
  expect_invalid([] { Sequential<double> s({.block_points = 4, .threads = -1}); },
                 {"SequentialOptions.threads", "-1"});
  Sequential<double> s;
  s.add(std::make_unique<fields::Dense<double>>(2, 4));
  expect_invalid([&] { s.add(std::make_unique<fields::Dense<double>>(3, 1)); },
                 {"takes width 3", "previous output is 4"});
  s.add(std::make_unique<fields::Dense<double>>(4, 1));
  EXPECT_EQ(s.parameter_count(), 2 * 4 + 4 + 4 + 1);
  EXPECT_EQ(s.parameter_offset(1), 12);
  Sequential<double> empty;
  Streams<double> out;
  const Eigen::MatrixXd x = Eigen::MatrixXd::Zero(1, 2);
  EXPECT_THROW(empty.evaluate(nullptr, StreamLayout(StreamSpec::values(2)), x, out),
               std::logic_error);
}

}  // namespace
}  // namespace nfield::autodiff
