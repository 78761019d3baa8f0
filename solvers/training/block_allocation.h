// SPDX-License-Identifier: MIT
//
// ACORN's training loop around its block tree (fields/acorn.h, fields/acorn_tree.h), as a
// training strategy (training_strategy.h) the trainer adds when its field is an acorn one
// (make_block_allocation); the trainer knows it by this one call.
//
//   every allocate_every steps (before_step)
//     1. error: each block's mean of ‖r‖² over the last step's points that fall in it (every
//        term whose points are coordinates of the field's box, one residual row each), times
//        the block's volume fraction: E_b, the block's share of the squared error integral.
//        Blocks without a point keep their last estimate.
//     2. freeze: an active block whose mean is below freeze_below (> 0) is frozen: no longer
//        sampled nor reallocated, and its feature grid at this step is kept in the tree
//        (fields::Block::grid) and read from then on instead of the shared encoder, which
//        would move it with no points there to hold it (ACORN prunes such blocks). Before
//        grids were kept, frozen blocks drifted into stray surfaces: 439 pieces on the
//        occupancy bunny (docs/experiments.md, 2026-11-27 session 24).
//     3. allocate: fields/acorn_allocation.h's exact optimum under max_blocks; the tree is
//        replaced, and the step draws new points.
//   every draw (points_drawn)
//     the term's n points are replaced by points in the active blocks, block b getting its
//     share n · V_b / Σ V of the n (the largest remainders rounded up), uniform inside the
//     block and stored block after block, so a pass of 128 points touches a few blocks and
//     the encoder runs a few times per pass (fields/acorn.h).
//
// The draws come from this strategy's own engine, seeded from training.seed, whose state is
// in the checkpoint beside the tree (which is the field's: fields/acorn_type.cc), so a
// resumed run draws what the uninterrupted one draws. Every rank runs the same hooks on the
// same points, so the draws and the allocation agree across ranks.
// Progress lines show `blocks` (active) and `frozen`; metrics.json adds acorn_blocks,
// acorn_frozen, acorn_splits and acorn_merges (totals over the run).
#pragma once

#include <memory>
#include <random>

#include "fields/acorn.h"
#include "fields/field.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {

template <typename Scalar>
class BlockAllocation final : public TrainingStrategy<Scalar> {
 public:
  // `field` an acorn field whose options carry its tree and box (encoding.lower/upper);
  // `terms` the trainer's loss terms.
  BlockAllocation(const fields::FieldOptions& field, std::uint64_t seed, std::size_t terms);

  bool before_step(StrategyView<Scalar>& view) override;
  void points_drawn(std::size_t k, TermPoints& points) override;
  void metrics(std::vector<std::pair<std::string, double>>& out) const override;
  void progress(std::vector<std::pair<std::string, double>>& out) const override;
  void save(io::H5Writer& file, const std::string& group) const override;
  void load(const io::H5Reader& file, const std::string& group) override;

  // Estimates the blocks' errors from squared residuals at points x (rows alike), freezes
  // and reallocates; returns whether the tree changed. before_step's work, for tests.
  // `field` (null in tests of the allocation alone): a block that freezes keeps its feature
  // grid at the field's parameters (fields::Block::grid); without it, it keeps none.
  bool reallocate(const Eigen::MatrixXd& x, const Eigen::VectorXd& squared,
                  const fields::Field<Scalar>* field = nullptr);

 private:
  // x mapped into the unit cube.
  void to_unit(const double* x, double* u) const;
  fields::AcornOptions options_;
  std::shared_ptr<fields::BlockTree> tree_;
  int dim_;
  std::size_t terms_;
  double lower_[3], range_[3];
  std::mt19937_64 rng_;
  long last_step_ = 0;
  long splits_ = 0, merges_ = 0;
};

// The strategy for an acorn field trained on `terms` loss terms, or null for any other field.
template <typename Scalar>
std::unique_ptr<TrainingStrategy<Scalar>> make_block_allocation(const fields::Field<Scalar>& field,
                                                                std::uint64_t seed, std::size_t terms);

}  // namespace nfield::solvers
