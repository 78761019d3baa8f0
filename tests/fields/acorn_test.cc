// SPDX-License-Identifier: MIT
//
// ACORN (fields/acorn.h): the block tree's tiling and lookup, the allocation against a brute
// force over every choice on small trees, the feature grid's interpolation, the value and
// gradient streams against central differences, the parameter gradient against finite
// differences, and the field with its tree through a checkpoint.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "autodiff/sequential.h"
#include "fields/acorn.h"
#include "fields/acorn_allocation.h"
#include "fields/acorn_tree.h"
#include "fields/field.h"
#include "fields/field_io.h"
#include "tests/testing/scratch.h"
#include "tests/testing/small_acorn.h"
#include "tests/testing/squares_loss.h"

namespace nfield::fields {
namespace {

// The 2-D tree of four level-1 blocks whose block (1, 1) is split into four at level 2.
std::vector<Block> split_corner() { return testutil::split_corner(2); }

TEST(AcornTree, TilesAndLocates) {
  BlockTree tree(2, 3, 1);
  EXPECT_EQ(tree.blocks().size(), 4u);
  tree.set_blocks(split_corner());
  const double inside[2] = {0.8, 0.6};  // in [0.75, 1) × [0.5, 0.75): block (2, 3, 2)
  const Block& b = tree.blocks()[static_cast<size_t>(tree.locate(inside))];
  EXPECT_EQ(b.level, 2);
  EXPECT_EQ(b.index[0], 3);
  EXPECT_EQ(b.index[1], 2);
  const double corner[2] = {0.1, 0.9};
  EXPECT_EQ(tree.blocks()[static_cast<size_t>(tree.locate(corner))].index[1], 1);
  std::vector<Block> gap = split_corner();
  gap.pop_back();
  EXPECT_THROW(tree.set_blocks(gap), std::invalid_argument);
  std::vector<Block> overlap = split_corner();
  overlap.push_back({1, {1, 1, 0}});
  EXPECT_THROW(tree.set_blocks(overlap), std::invalid_argument);
  EXPECT_EQ(tree.blocks().size(), 7u);  // a refused layout leaves the tree as it was
  EXPECT_EQ(tree.blocks()[static_cast<size_t>(tree.locate(inside))].index[0], 3);
  EXPECT_THROW(BlockTree(2, 11, 1), std::invalid_argument);
}

// Over all 3^n choices: the least cost with at most c blocks, for c = 0 … max (+∞ when no
// choice fits).
std::vector<double> brute_force(const std::vector<Block>& blocks, int dim, int max_level, double beta) {
  const size_t n = blocks.size();
  std::vector<BlockChoice> c(n, BlockChoice::kKeep);
  std::vector<double> best(n * (1u << dim) + 1, std::numeric_limits<double>::infinity());
  long combos = 1;
  for (size_t i = 0; i < n; ++i) combos *= 3;
  for (long k = 0; k < combos; ++k) {
    long rest = k;
    for (size_t i = 0; i < n; ++i, rest /= 3) c[i] = static_cast<BlockChoice>(rest % 3);
    const Allocation a = evaluate_allocation(blocks, dim, max_level, beta, c);
    double& slot = best[static_cast<size_t>(a.blocks)];
    slot = std::min(slot, a.cost);
  }
  for (size_t k = 1; k < best.size(); ++k) best[k] = std::min(best[k], best[k - 1]);
  return best;
}

void expect_optimal(std::vector<Block> blocks, int dim, int max_level, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> error(0.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    for (Block& b : blocks) b.error = error(rng) * error(rng);
    const double beta = trial % 2 ? 0.25 : 0.6;
    const std::vector<double> least = brute_force(blocks, dim, max_level, beta);
    for (int budget = 1; budget < static_cast<int>(least.size()); ++budget) {
      const double best = least[static_cast<size_t>(budget)];
      if (!std::isfinite(best)) continue;  // no choice fits so small a budget
      const Allocation a = allocate_blocks(blocks, dim, max_level, budget, beta);
      EXPECT_NEAR(a.cost, best, 1e-12 * std::max(1.0, best)) << "budget " << budget;
      EXPECT_LE(a.blocks, budget);
      const Allocation check = evaluate_allocation(blocks, dim, max_level, beta, a.choices);
      EXPECT_NEAR(check.cost, a.cost, 1e-12 * std::max(1.0, best));
      EXPECT_EQ(check.blocks, a.blocks);
      // The result tiles the cube.
      BlockTree tree(dim, max_level, 0);
      EXPECT_NO_THROW(tree.set_blocks(apply_allocation(blocks, dim, a.choices)));
      EXPECT_EQ(static_cast<int>(tree.blocks().size()), a.blocks);
    }
  }
}

TEST(AcornAllocation, MatchesBruteForceOnSmallTrees) {
  std::mt19937_64 rng(7);
  expect_optimal(split_corner(), 2, 3, rng);  // 7 blocks: one complete group of 4
  std::vector<Block> two = split_corner();    // 10 blocks: a second group, one at max_level
  two.erase(two.begin());
  for (int i = 0; i < 4; ++i) two.push_back({2, {i % 2, i / 2, 0}});
  expect_optimal(two, 2, 2, rng);
  std::vector<Block> frozen = split_corner();  // a frozen member: that group cannot merge
  frozen[4].frozen = true;
  expect_optimal(frozen, 2, 3, rng);
  std::vector<Block> line;  // 1-D, levels 1 to 3
  line.push_back({1, {0, 0, 0}});
  line.push_back({2, {2, 0, 0}});
  line.push_back({3, {6, 0, 0}});
  line.push_back({3, {7, 0, 0}});
  expect_optimal(line, 1, 4, rng);
  std::vector<Block> cube;  // 3-D: the eight children of the root
  for (int i = 0; i < 8; ++i) cube.push_back({1, {i & 1, (i >> 1) & 1, i >> 2}});
  expect_optimal(cube, 3, 2, rng);
}

TEST(AcornAllocation, SplitsWhereTheErrorIs) {
  std::vector<Block> blocks = split_corner();
  for (Block& b : blocks) b.error = 1e-6;
  blocks[0].error = 1.0;
  const Allocation a = allocate_blocks(blocks, 2, 3, 10, 0.25);
  EXPECT_EQ(a.choices[0], BlockChoice::kSplit);
  // Within 10 blocks the split fits beside the quiet group; within 7 it needs their merge.
  const Allocation tight = allocate_blocks(blocks, 2, 3, 7, 0.25);
  EXPECT_EQ(tight.choices[0], BlockChoice::kSplit);
  EXPECT_EQ(tight.choices[3], BlockChoice::kMerge);
  EXPECT_EQ(tight.blocks, 7);
}

FieldOptions small_acorn(int dim, const std::string& activation = "tanh") {
  FieldOptions o;
  o.type = "acorn";
  o.input_dim = dim;
  o.output_dim = 2;
  o.hidden = {6};
  o.activation = activation;
  o.encoding.lower.assign(static_cast<size_t>(dim), -1.0);
  o.encoding.upper.assign(static_cast<size_t>(dim), 1.0);
  o.extension = testutil::small_acorn_options();
  acorn_tree(o);
  if (dim == 2) acorn_tree(o)->set_blocks(split_corner());
  o.seed = 3;
  return o;
}

// Points of [−1, 1]^d at least `margin` grid steps from every cell face of their block.
Eigen::MatrixXd inner_points(const FieldOptions& o, int n, std::mt19937_64& rng, double margin = 0.05) {
  const BlockTree& tree = *acorn_options(o).tree;
  const int g = acorn_options(o).grid;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd x(n, o.input_dim);
  for (int p = 0; p < n;) {
    double v[3];
    for (int j = 0; j < o.input_dim; ++j) v[j] = u(rng);
    const int b = tree.locate(v);
    bool ok = true;
    for (int j = 0; j < o.input_dim; ++j) {
      const double step = (v[j] - tree.lower(b, j)) / tree.size(b) * (g - 1);
      ok = ok && std::abs(step - std::round(step)) > margin;
    }
    if (!ok) continue;
    for (int j = 0; j < o.input_dim; ++j) x(p, j) = 2 * v[j] - 1;
    ++p;
  }
  return x;
}

TEST(AcornField, InterpolatesTheBlockGrid) {
  const FieldOptions o = small_acorn(2);
  Field<double> field(o);
  const auto& module = dynamic_cast<const AcornEncoding<double>&>(*field.network().modules()[0]);
  const BlockTree& tree = *acorn_options(o).tree;
  autodiff::StreamLayout layout(autodiff::StreamSpec::values(2));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int b = 0; b < static_cast<int>(tree.blocks().size()); ++b) {
    const Eigen::VectorXd grid = module.block_grid(field.parameters().data(), b);
    // A point at fractions (s0, s1) of grid cell (1, 2) of block b.
    const double s0 = u(rng), s1 = u(rng);
    Eigen::MatrixXd x(1, 2);
    x(0, 0) = 2 * (tree.lower(b, 0) + (1 + s0) / 3 * tree.size(b)) - 1;
    x(0, 1) = 2 * (tree.lower(b, 1) + (2 + s1) / 3 * tree.size(b)) - 1;
    autodiff::Streams<double> in, out;
    autodiff::seed_input_streams<double>(layout, x, in);
    module.forward(layout, field.parameters().data(), in, out, nullptr);
    for (int c = 0; c < 3; ++c) {
      auto at = [&](int i, int j) { return grid((i + 4 * j) * 3 + c); };
      const double want = (1 - s0) * (1 - s1) * at(1, 2) + s0 * (1 - s1) * at(2, 2) +
                          (1 - s0) * s1 * at(1, 3) + s0 * s1 * at(2, 3);
      EXPECT_NEAR(out.data(0, c), want, 1e-12) << "block " << b;
    }
  }
}

TEST(AcornField, GradientStreamMatchesCentralDifferences) {
  for (int dim : {1, 2, 3}) {
    const FieldOptions o = small_acorn(dim);
    Field<double> field(o);
    std::mt19937_64 rng(11);
    const Eigen::MatrixXd x = inner_points(o, 40, rng);
    autodiff::StreamLayout layout(autodiff::StreamSpec::gradient(dim));
    autodiff::Streams<double> out;
    field.evaluate(layout, x, out);
    const Eigen::MatrixXd values = field.values(x);
    EXPECT_LT((out.stream(0) - values).cwiseAbs().maxCoeff(), 1e-14);
    const double h = 1e-6;
    for (int j = 0; j < dim; ++j) {
      Eigen::MatrixXd up = x, down = x;
      up.col(j).array() += h;
      down.col(j).array() -= h;
      const Eigen::MatrixXd fd = (field.values(up) - field.values(down)) / (2 * h);
      EXPECT_LT((out.stream(layout.tangent(j)) - fd).cwiseAbs().maxCoeff(), 1e-7) << "dim " << dim << " axis " << j;
    }
    // Points in any order give the same values as one at a time (the per-pass block slots).
    for (Eigen::Index p = 0; p < x.rows(); p += 7)
      EXPECT_LT((field.values(x.row(p)) - values.row(p)).cwiseAbs().maxCoeff(), 1e-15);
  }
}

TEST(AcornField, ParameterGradientMatchesFiniteDifferences) {
  const FieldOptions o = small_acorn(2);
  Field<double> field(o);
  std::mt19937_64 rng(13);
  const Eigen::MatrixXd x = inner_points(o, 300, rng);
  autodiff::StreamLayout layout(autodiff::StreamSpec::gradient(2));
  field.set_evaluation({32, 1});  // several passes, several blocks each
  testutil::SquaresLoss<double> loss(Eigen::MatrixXd::Ones(3, 2));
  const Eigen::Index n = field.parameter_count();
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(n);
  const autodiff::Batch<double> batch{x};
  field.value_and_gradient(field.parameters().data(), layout, batch, loss, gradient.data());
  auto total = [&](const Eigen::VectorXd& theta) {
    autodiff::Streams<double> out;
    field.evaluate(theta.data(), layout, batch, out);
    return loss.value(out);
  };
  const Eigen::VectorXd theta = field.parameters();
  std::uniform_int_distribution<Eigen::Index> pick(0, n - 1);
  double worst = 0;
  for (int k = 0; k < 60; ++k) {
    const Eigen::Index i = k < 10 ? k : pick(rng);  // the encoder's first weights too
    Eigen::VectorXd up = theta, down = theta;
    const double h = 1e-6;
    up(i) += h;
    down(i) -= h;
    const double fd = (total(up) - total(down)) / (2 * h);
    worst = std::max(worst, std::abs(fd - gradient(i)) / std::max(1.0, std::abs(fd)));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(gradient.head(10).cwiseAbs().maxCoeff(), 0);  // the encoder is trained
}

TEST(AcornField, RefusesStreamsItLacks) {
  Field<double> field(small_acorn(2));
  autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  autodiff::Streams<double> out;
  const Eigen::MatrixXd x = Eigen::MatrixXd::Zero(2, 2);
  try {
    field.evaluate(layout, x, out);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("operator and Taylor"), std::string::npos) << e.what();
  }
}

TEST(AcornField, RoundTripsThroughACheckpoint) {
  FieldOptions o = small_acorn(2);
  Field<float> field(o);
  std::vector<Block> blocks = split_corner();
  blocks[1].frozen = true;
  blocks[5].error = 0.125;
  acorn_tree(o)->set_blocks(blocks);  // the field's tree: shared with its options
  const auto path = testutil::scratch_dir("acorn") / "acorn.h5";
  {
    io::H5Writer file(path);
    save_field(file, field);
    file.commit();
  }
  io::H5Reader file(path);
  const Field<float> loaded = load_field<float>(file);
  const BlockTree& tree = *acorn_options(loaded.options()).tree;
  ASSERT_EQ(tree.blocks().size(), blocks.size());
  for (size_t b = 0; b < blocks.size(); ++b) {
    EXPECT_EQ(tree.blocks()[b].level, blocks[b].level);
    EXPECT_EQ(tree.blocks()[b].index, blocks[b].index);
    EXPECT_EQ(tree.blocks()[b].frozen, blocks[b].frozen);
    EXPECT_EQ(tree.blocks()[b].error, blocks[b].error);
  }
  EXPECT_NE(acorn_options(loaded.options()).tree, acorn_options(o).tree);  // its own copy
  std::mt19937_64 rng(17);
  const Eigen::MatrixXf x = inner_points(o, 64, rng).cast<float>();
  EXPECT_EQ(loaded.values(x), field.values(x));
  EXPECT_EQ(acorn_options(loaded.options()).max_blocks, 64);
}

}  // namespace
}  // namespace nfield::fields
