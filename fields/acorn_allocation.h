// SPDX-License-Identifier: MIT
//
// ACORN's block allocation (Martel et al. 2021, Sec. 3.3) without an integer-programming
// solver: an exact dynamic program over the same costs.
//
// The problem. Each active (not frozen) leaf i of the block tree (fields/acorn_tree.h), with
// estimated error E_i (its mean squared error × its volume fraction), takes one of
//   keep    1 block,     cost E_i
//   split   2^d blocks,  cost β E_i            (not at max_level)
//   merge   with its 2^d siblings into their parent: 1 block for the group, cost Σ_sib E / β
//           (only when all 2^d siblings are active leaves and all of them merge)
// and frozen leaves keep (1 block, cost E_i). β = split_factor ∈ (0, 1) models how a block's
// error changes with its size: each child gets a whole feature grid for 2^−d of the volume,
// so its error is taken as a fixed fraction of the parent's, and merging is the inverse.
// Minimise Σ cost subject to Σ blocks ≤ budget. This has the structure of the paper's
// integer program (a one-hot choice per block, the constraint that siblings merge together,
// one knapsack row for the budget); the paper's own weighting of the split and merge terms
// is replaced here by the single factor β (a modelling choice, not taken from the paper).
//
// The solution. Group the leaves into items that do not interact: a complete sibling group
// (2^d active leaves of one parent) is one item with options "merge" (1 block) or any
// combination of keep/split of its members (2^(2^d) ≤ 256 combinations, the cheapest kept
// per block count); every other leaf is an item with keep/split. Items interact only through
// the budget, so the optimum is a multiple-choice knapsack over integer block counts:
//   D_k(c) = min over item k's options o with count n_o ≤ c of D_{k−1}(c − n_o) + cost_o,
// D_0(0) = 0, and the answer min_c≤B D_K(c). Counts are integers bounded by B, so the
// program is exact (no rounding, unlike an LP relaxation) in O(K · B · options) time, and a
// table of each item's chosen option per count recovers the choices. Keeping every block is
// always feasible when the tree's current count is within the budget; when it is not (a
// smaller budget on resume), the program merges where it can, and what cannot fit is kept.
//
// Ties: lower cost first, then fewer blocks (deterministic: items in tree order).
#pragma once

#include <vector>

#include "fields/acorn_tree.h"

namespace nfield::fields {

enum class BlockChoice { kKeep, kSplit, kMerge };

struct Allocation {
  std::vector<BlockChoice> choices;  // one per leaf, in the tree's order
  double cost = 0;                   // the estimated total error after it
  int blocks = 0;                    // leaves after it
};

// The optimal choices for `blocks` (a valid tiling, fields/acorn_tree.h) of dimension `dim`.
// budget ≥ 1, 0 < split_factor < 1.
Allocation allocate_blocks(const std::vector<Block>& blocks, int dim, int max_level, int budget,
                           double split_factor);

// The cost and block count of any choices, for checks: +∞ cost when the choices are not
// allowed (a split at max_level or of a frozen block, a merge of an incomplete, frozen or
// partly merging sibling group).
Allocation evaluate_allocation(const std::vector<Block>& blocks, int dim, int max_level,
                               double split_factor, std::vector<BlockChoice> choices);

// The leaves after the choices (children and parents with error 0, not frozen), in a
// deterministic order: kept blocks, then children in index order, then merged parents.
std::vector<Block> apply_allocation(const std::vector<Block>& blocks, int dim,
                                    const std::vector<BlockChoice>& choices);

}  // namespace nfield::fields
