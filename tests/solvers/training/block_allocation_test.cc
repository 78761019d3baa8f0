// SPDX-License-Identifier: MIT
//
// ACORN's frozen blocks (solvers/training/block_allocation.h, fields::Block::grid): a block
// that freezes keeps its feature grid at that step, so its values stay put while training
// moves the shared encoder for the other blocks, its points pass no gradient to the encoder,
// and the kept grids come back from a checkpoint.
#include <gtest/gtest.h>

#include <vector>

#include "fields/acorn.h"
#include "fields/field.h"
#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "solvers/training/block_allocation.h"
#include "tests/testing/scratch.h"
#include "tests/testing/small_acorn.h"
#include "tests/testing/squares_loss.h"

namespace nfield::solvers {
namespace {

// A 2-D acorn field over [−1, 1]² with the small test encoder, blocks of levels 1 and 2.
fields::FieldOptions small_field() {
  fields::FieldOptions o;
  o.type = "acorn";
  o.input_dim = 2;
  o.output_dim = 1;
  o.hidden = {6};
  o.activation = "tanh";
  o.encoding.lower = {-1.0, -1.0};
  o.encoding.upper = {1.0, 1.0};
  fields::AcornOptions a = testutil::small_acorn_options();
  a.freeze_below = 1e-3;
  a.allocate_every = 1;
  o.extension = a;
  fields::acorn_tree(o)->set_blocks(testutil::split_corner(2));
  o.seed = 5;
  return o;
}

// Points at the centres of a 16 × 16 grid over the box.
Eigen::MatrixXd grid_points() {
  Eigen::MatrixXd x(256, 2);
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j) x.row(i * 16 + j) << -1 + (2 * i + 1) / 16.0, -1 + (2 * j + 1) / 16.0;
  return x;
}

// Which block of the tree each point is in.
std::vector<int> blocks_of(const fields::BlockTree& tree, const Eigen::MatrixXd& x) {
  std::vector<int> out;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    const double u[2] = {(x(p, 0) + 1) / 2, (x(p, 1) + 1) / 2};
    out.push_back(tree.locate(u));
  }
  return out;
}

TEST(BlockAllocation, FrozenBlocksKeepTheirGrid) {
  const fields::FieldOptions o = small_field();
  fields::Field<double> field(o);
  const fields::BlockTree& tree = *fields::acorn_options(o).tree;
  BlockAllocation<double> allocation(o, 1, 1);
  const Eigen::MatrixXd x = grid_points();
  std::vector<int> block = blocks_of(tree, x);
  // Block 0 (the lower-left level-1 block) has no error: it freezes; the others' is large.
  Eigen::VectorXd squared(x.rows());
  for (Eigen::Index p = 0; p < x.rows(); ++p) squared(p) = block[static_cast<size_t>(p)] == 0 ? 0.0 : 1.0;
  const auto& encoding = dynamic_cast<const fields::AcornEncoding<double>&>(*field.network().modules()[0]);
  const Eigen::VectorXd before_grid = encoding.block_grid(field.parameters().data(), 0);
  allocation.reallocate(x, squared, &field);
  // The others may have split: the frozen block is the one at level 1, index (0, 0).
  int frozen_blocks = 0;
  for (const fields::Block& b : tree.blocks()) {
    if (!b.frozen) {
      EXPECT_TRUE(b.grid.empty());
      continue;
    }
    ++frozen_blocks;
    EXPECT_EQ(b.level, 1);
    EXPECT_EQ(b.index[0] + b.index[1], 0);
    ASSERT_EQ(b.grid.size(), static_cast<size_t>(before_grid.size()));
    EXPECT_EQ(Eigen::Map<const Eigen::VectorXd>(b.grid.data(), before_grid.size()), before_grid);
  }
  EXPECT_EQ(frozen_blocks, 1);

  // The frozen block keeps its values when the encoder moves; the others move.
  block = blocks_of(tree, x);
  const Eigen::MatrixXd before = field.values(x);
  field.parameters().head(encoding.parameter_count()).array() += 0.05;
  const Eigen::MatrixXd after = field.values(x);
  int frozen_points = 0;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    if (tree.blocks()[static_cast<size_t>(block[static_cast<size_t>(p)])].frozen) {
      ++frozen_points;
      EXPECT_EQ(after(p, 0), before(p, 0)) << p;
    } else {
      EXPECT_NE(after(p, 0), before(p, 0)) << p;
    }
  }
  EXPECT_GT(frozen_points, 0);

  // Points in the frozen block give the decoder a gradient and the encoder none.
  Eigen::MatrixXd inside(frozen_points, 2);
  for (Eigen::Index p = 0, k = 0; p < x.rows(); ++p)
    if (tree.blocks()[static_cast<size_t>(block[static_cast<size_t>(p)])].frozen) inside.row(k++) = x.row(p);
  testutil::SquaresLoss<double> loss(Eigen::MatrixXd::Ones(1, 1));
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(field.parameter_count());
  autodiff::StreamLayout layout(autodiff::StreamSpec::values(2));
  field.value_and_gradient(field.parameters().data(), layout, autodiff::Batch<double>{inside}, loss, gradient.data());
  EXPECT_EQ(gradient.head(encoding.parameter_count()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(gradient.tail(field.parameter_count() - encoding.parameter_count()).cwiseAbs().maxCoeff(), 0.0);

  // The kept grid is in the checkpoint: the loaded field gives the same values.
  const auto path = testutil::scratch_dir("block_allocation") / "frozen.h5";
  {
    io::H5Writer file(path);
    fields::save_field(file, field);
    file.commit();
  }
  const io::H5Reader file(path);
  const fields::Field<double> loaded = fields::load_field<double>(file);
  const fields::BlockTree& loaded_tree = *fields::acorn_options(loaded.options()).tree;
  ASSERT_EQ(loaded_tree.blocks().size(), tree.blocks().size());
  for (size_t b = 0; b < tree.blocks().size(); ++b) EXPECT_EQ(loaded_tree.blocks()[b].grid, tree.blocks()[b].grid) << b;
  EXPECT_EQ(loaded.values(x), after);
}

}  // namespace
}  // namespace nfield::solvers
