// SPDX-License-Identifier: MIT
//
// ACORN's block tree (Martel et al., ACORN: Adaptive Coordinate Networks for Neural Scene
// Representation, SIGGRAPH 2021, Sec. 3.2): the unit cube [0, 1]^d (the field's box, scaled)
// tiled by the leaves of a quadtree (d = 2) or octree (d = 3). A leaf at level l is the cube
// [i 2^−l, (i + 1) 2^−l) per axis, i = index[j] ∈ [0, 2^l); its parent is (l − 1, i >> 1) and
// its siblings the 2^d leaves with the same parent. Only leaves are stored: they are the
// "active" blocks the field fits, each with its estimated error and a frozen flag (a block
// whose error fell below training's threshold is no longer sampled nor reallocated).
//
// Lookup: a dense table over the finest cells (2^max_level per axis) holds the leaf of each
// cell, so locate() costs a multiply per axis and one load. max_level is bounded so the table
// stays small: 2^(d·max_level) ≤ 2^21 entries (2-D: level 10; 3-D: level 7).
//
// The tree is the field's state, not a config value: fields::AcornOptions holds it by shared
// pointer, so a field and its casts (Field::cast) see one tree, the allocation
// (fields/acorn_allocation.h) changes it between steps, and checkpoints save it with the field.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace nfield::fields {

struct Block {
  int level = 0;
  std::array<int, 3> index{0, 0, 0};
  bool frozen = false;
  double error = 0;  // the last estimate: mean squared error × the block's volume fraction
  // A frozen block's feature grid as it was when the block froze (C · G^d, fields/acorn.h's
  // layout), read instead of the encoder's: the encoder is shared, so a frozen block that read
  // it would drift as training moves it for the other blocks, with no points there to hold
  // it (ACORN prunes such blocks). Empty: the block reads the encoder.
  std::vector<double> grid;
};

// Largest max_level for a dimension (the lookup table's bound above).
int max_tree_level(int dim);

class BlockTree {
 public:
  // The uniform tiling at `initial_level`; dim 1 … 3, 0 ≤ initial_level ≤ max_level ≤
  // max_tree_level(dim) (std::invalid_argument otherwise).
  BlockTree(int dim, int max_level, int initial_level);

  int dim() const { return dim_; }
  int max_level() const { return max_level_; }
  const std::vector<Block>& blocks() const { return blocks_; }
  std::vector<Block>& mutable_blocks() { return blocks_; }  // errors and flags only
  int active() const;  // blocks not frozen
  int frozen() const { return static_cast<int>(blocks_.size()) - active(); }
  // Bumped by every set_blocks: a pass or a sampler can tell the layout changed.
  std::uint64_t version() const { return version_; }

  // Replaces the leaves; throws std::invalid_argument, the tree unchanged, unless they tile
  // the cube exactly (no gap, no overlap) within max_level.
  void set_blocks(std::vector<Block> blocks);

  // The leaf holding u ∈ [0, 1]^d (clamped into the cube; NaN goes to cell 0).
  template <typename Scalar>
  int locate(const Scalar* u) const {
    const int cells = 1 << max_level_;
    std::int64_t cell = 0, stride = 1;
    for (int j = 0; j < dim_; ++j) {
      const Scalar p = u[j] * static_cast<Scalar>(cells);
      int c = p >= 0 ? static_cast<int>(p) : 0;
      if (c >= cells) c = cells - 1;
      cell += c * stride;
      stride *= cells;
    }
    return lookup_[static_cast<std::size_t>(cell)];
  }
  // Edge length 2^−level and lower corner of block b, in the unit cube.
  double size(int b) const;
  double lower(int b, int axis) const;
  // The volume fraction 2^(−d·level).
  double volume(int b) const;

 private:
  // The lookup table of `blocks`; throws std::invalid_argument for a gap or an overlap.
  std::vector<std::int32_t> lookup_of(const std::vector<Block>& blocks) const;
  int dim_, max_level_;
  std::vector<Block> blocks_;
  std::vector<std::int32_t> lookup_;
  std::uint64_t version_ = 0;
};

}  // namespace nfield::fields
