// SPDX-License-Identifier: MIT
//
// The elementwise rules run over a few columns of every stream at a time (chunk_columns in
// autodiff/elementwise.cc: 4096 / points columns). Every column's rules are independent of
// the others', so a wide layer must give, column for column, what the same rules give on that
// column alone; with 1024 points a chunk is 4 columns and 11 columns cross two whole chunks
// and a partial one. The tables are random: the rules are linear in them.
#include <gtest/gtest.h>

#include <vector>

#include "autodiff/elementwise.h"

namespace nfield::autodiff {
namespace {

constexpr Eigen::Index kPoints = 1024, kWidth = 11;

StreamLayout rich_layout() {
  StreamSpec spec = StreamSpec::laplacian(3);
  Eigen::MatrixXd mixed(3, 3);
  mixed << 1.0, 0.5, 0.0, 0.5, -2.0, 0.25, 0.0, 0.25, 3.0;
  spec.add_operator(mixed);
  spec.set_taylor(Eigen::MatrixXd::Identity(3, 2), 3);
  return StreamLayout(spec);
}

Streams<double> random_streams(const StreamLayout& layout, Eigen::Index width) {
  Streams<double> s;
  s.resize(kPoints, layout.count(), width);
  s.data.setRandom();
  return s;
}

Streams<double> column(const Streams<double>& s, Eigen::Index c) {
  Streams<double> one;
  one.resize(s.points, s.count, 1);
  one.data = s.data.col(c);
  return one;
}

TEST(ElementwiseChunks, EveryColumnMatchesThatColumnAlone) {
  const StreamLayout layout = rich_layout();
  std::vector<Matrix<double>> tables(layout.forward_order() + 2);
  for (auto& t : tables) t = Matrix<double>::Random(kPoints, kWidth);
  const Streams<double> z = random_streams(layout, kWidth), y_bar = random_streams(layout, kWidth);
  Streams<double> y, z_bar;
  elementwise_forward(layout, tables, z, y);
  elementwise_backward(layout, tables, z, y_bar, z_bar);
  for (Eigen::Index c = 0; c < kWidth; ++c) {
    std::vector<Matrix<double>> column_tables;
    for (const auto& t : tables) column_tables.push_back(t.col(c));
    Streams<double> y_c, z_bar_c;
    elementwise_forward(layout, column_tables, column(z, c), y_c);
    elementwise_backward(layout, column_tables, column(z, c), column(y_bar, c), z_bar_c);
    EXPECT_EQ((y.data.col(c) - y_c.data).cwiseAbs().maxCoeff(), 0.0) << "forward, column " << c;
    EXPECT_EQ((z_bar.data.col(c) - z_bar_c.data).cwiseAbs().maxCoeff(), 0.0) << "backward, column " << c;
  }
}

}  // namespace
}  // namespace nfield::autodiff
