// SPDX-License-Identifier: MIT
//
// Passes over a Batch: groups of points that one loss reads together stay in one block
// (whatever block_points and the thread count), the gradient of a loss over groups does not
// depend on how the groups are packed into blocks, and per-point tangent directions give
// each point the derivative along its own direction (checked against the shared-direction
// pass one point at a time and against central differences).
#include <gtest/gtest.h>

#include <atomic>
#include <random>

#include "autodiff/sequential.h"
#include "fields/field.h"

namespace nfield::autodiff {
namespace {

fields::Field<double> small_siren(int input_dim) {
  fields::FieldOptions o;
  o.input_dim = input_dim;
  o.hidden = {16, 16};
  o.first_omega = 3;
  o.seed = 5;
  return fields::Field<double>(o);
}

Eigen::MatrixXd random_points(Eigen::Index n, int d, unsigned seed) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd x(n, d);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return x;
}

// Offsets of groups of sizes 0, 1, 2, … cycling up to `largest`: empty groups, groups larger
// than a block and groups at the end all occur.
std::vector<Eigen::Index> cycling_groups(int count, int largest) {
  std::vector<Eigen::Index> offsets{0};
  for (int k = 0; k < count; ++k) offsets.push_back(offsets.back() + k % (largest + 1));
  offsets.push_back(offsets.back());  // an empty group at the very end
  return offsets;
}

// L = Σ_groups (Σ_{n ∈ g} u_n)² + 0.5: reads all points of a group at once (a ray's
// colour is such a function of its samples). Counts groups it saw cut by a block edge.
class GroupSquares final : public StreamLoss<double> {
 public:
  explicit GroupSquares(std::vector<Eigen::Index> groups) : groups_(std::move(groups)) {}
  double evaluate(Eigen::Index first, const StreamLayout&, const Streams<double>& out,
                  Streams<double>& adjoint) const override {
    const auto [k0, k1] = groups_in_block(groups_, first, out.points);
    double loss = 0;
    for (size_t k = k0; k < k1; ++k) {
      const Eigen::Index begin = groups_[k] - first, end = groups_[k + 1] - first;
      if (begin < 0 || end > out.points) {
        ++cut_groups;
        continue;
      }
      const double sum = out.stream(0).col(0).segment(begin, end - begin).sum();
      loss += sum * sum + 0.5;
      adjoint.stream(0).col(0).segment(begin, end - begin).setConstant(2 * sum);
      ++seen_groups;
    }
    return loss;
  }
  mutable std::atomic<int> cut_groups{0}, seen_groups{0};

 private:
  std::vector<Eigen::Index> groups_;
};

TEST(Batch, BlocksAreCutBetweenGroupsOnly) {
  Sequential<double> network(SequentialOptions{.block_points = 4});
  const std::vector<Eigen::Index> groups = cycling_groups(12, 6);
  const Eigen::Index n = groups.back();
  const std::vector<Eigen::Index> starts = network.block_starts(n, groups);
  EXPECT_EQ(starts.front(), 0);
  EXPECT_EQ(starts.back(), n);
  for (size_t b = 1; b + 1 < starts.size(); ++b) {
    EXPECT_NE(std::find(groups.begin(), groups.end(), starts[b]), groups.end())
        << "block edge " << starts[b] << " cuts a group";
    EXPECT_GT(starts[b], starts[b - 1]);
  }
  // Every group start lies in exactly one block's range.
  std::vector<int> owners(groups.size() - 1, 0);
  for (size_t b = 0; b + 1 < starts.size(); ++b) {
    const auto [k0, k1] = groups_in_block(groups, starts[b], starts[b + 1] - starts[b]);
    for (size_t k = k0; k < k1; ++k) ++owners[k];
  }
  for (size_t k = 0; k < owners.size(); ++k) EXPECT_EQ(owners[k], 1) << "group " << k;
  // Without groups: every block_points points.
  EXPECT_EQ(network.block_starts(10, {}), (std::vector<Eigen::Index>{0, 4, 8, 10}));
  EXPECT_EQ(network.block_starts(0, {}), (std::vector<Eigen::Index>{0}));
}

TEST(Batch, GroupOffsetsThatAreNoPartitionAreRejected) {
  Sequential<double> network;
  const std::vector<Eigen::Index> decreasing{0, 3, 2, 5}, short_end{0, 2, 4}, late_start{1, 5};
  EXPECT_THROW(network.block_starts(5, decreasing), std::invalid_argument);
  EXPECT_THROW(network.block_starts(5, short_end), std::invalid_argument);
  EXPECT_THROW(network.block_starts(5, late_start), std::invalid_argument);
  try {
    network.block_starts(5, decreasing);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must not decrease"), std::string::npos) << e.what();
  }
}

TEST(Batch, GroupLossGradientDoesNotDependOnBlocksOrThreads) {
  fields::Field<double> field = small_siren(2);
  const std::vector<Eigen::Index> groups = cycling_groups(40, 9);
  const Eigen::MatrixXd x = random_points(groups.back(), 2, 11);
  const StreamLayout layout(StreamSpec::values(2));
  const Batch<double> batch{x, nullptr, groups};

  auto gradient = [&](Eigen::Index block, int threads, double* loss) {
    field.network().set_options({block, threads});
    GroupSquares group_loss(groups);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(field.parameter_count());
    *loss = field.network().value_and_gradient(field.parameters().data(), layout, batch,
                                               group_loss, g.data());
    EXPECT_EQ(group_loss.cut_groups.load(), 0) << "block " << block << ", threads " << threads;
    EXPECT_EQ(group_loss.seen_groups.load(), static_cast<int>(groups.size()) - 1);
    return g;
  };
  double reference_loss;
  const Eigen::VectorXd reference = gradient(1 << 20, 1, &reference_loss);
  for (Eigen::Index block : {1, 3, 8, 64})
    for (int threads : {1, 2}) {
      double loss;
      const Eigen::VectorXd g = gradient(block, threads, &loss);
      EXPECT_NEAR(loss, reference_loss, 1e-12 * reference_loss);
      EXPECT_LE((g - reference).norm(), 1e-12 * reference.norm()) << "block " << block;
    }

  // And it is the gradient of L: a central difference along a random direction.
  std::mt19937_64 rng(3);
  Eigen::VectorXd u(field.parameter_count());
  for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = static_cast<double>(rng() >> 11) * 0x1.0p-53 - 0.5;
  const Eigen::VectorXd theta = field.parameters();
  auto loss_at = [&](double h) {
    field.parameters() = theta + h * u;
    const Eigen::MatrixXd values = field.values(x);
    double l = 0;
    for (size_t k = 0; k + 1 < groups.size(); ++k) {
      const double s = values.col(0).segment(groups[k], groups[k + 1] - groups[k]).sum();
      l += s * s + 0.5;
    }
    return l;
  };
  const double h = 1e-6;
  const double fd = (loss_at(h) - loss_at(-h)) / (2 * h);
  field.parameters() = theta;
  EXPECT_NEAR(reference.dot(u), fd, 1e-6 * std::abs(fd));
  EXPECT_NEAR(loss_at(0), reference_loss, 1e-10 * reference_loss);
}

TEST(Batch, PerPointTangentsAreEachPointsOwnDirection) {
  fields::Field<double> field = small_siren(3);
  const Eigen::Index n = 37;
  const Eigen::MatrixXd x = random_points(n, 3, 21);
  // Two directions per point: a unit "ray direction" and another, different per point.
  Eigen::MatrixXd directions = random_points(n, 6, 22).array() - 0.5;
  for (Eigen::Index i = 0; i < n; ++i) directions.row(i).head(3).normalize();
  StreamSpec spec;
  spec.input_dim = 3;
  spec.tangents = Eigen::MatrixXd::Zero(3, 2);  // replaced per point
  spec.add_operator(Eigen::Matrix2d{{1, 0.5}, {0.5, -2}});
  const StreamLayout layout(spec);
  field.network().set_options({8, 2});
  Streams<double> out;
  field.network().evaluate(field.parameters().data(), layout, Batch<double>{x, &directions}, out);

  for (Eigen::Index i = 0; i < n; ++i) {
    StreamSpec own = spec;
    own.tangents.col(0) = directions.row(i).head(3).transpose();
    own.tangents.col(1) = directions.row(i).tail(3).transpose();
    const StreamLayout own_layout(own);
    Streams<double> one;
    field.evaluate(own_layout, x.row(i), one);
    for (int s = 0; s < layout.count(); ++s)
      EXPECT_NEAR(out.stream(s)(i, 0), one.stream(s)(0, 0), 1e-12 * (1 + std::abs(one.stream(s)(0, 0))))
          << "point " << i << ", stream " << s;
    // Central difference along the point's first direction.
    const double h = 1e-5;
    const Eigen::RowVectorXd v = directions.row(i).head(3);
    const double fd = (field.values(x.row(i) + h * v)(0, 0) - field.values(x.row(i) - h * v)(0, 0)) / (2 * h);
    EXPECT_NEAR(out.stream(layout.tangent(0))(i, 0), fd, 1e-6 * (1 + std::abs(fd)));
  }

  const Eigen::MatrixXd wrong = directions.leftCols(3);
  EXPECT_THROW(field.network().evaluate(field.parameters().data(), layout, Batch<double>{x, &wrong}, out),
               std::invalid_argument);
}

}  // namespace
}  // namespace nfield::autodiff
