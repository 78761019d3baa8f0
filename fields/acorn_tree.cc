// SPDX-License-Identifier: MIT
#include "fields/acorn_tree.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace nfield::fields {

int max_tree_level(int dim) { return dim <= 1 ? 20 : 21 / dim; }

BlockTree::BlockTree(int dim, int max_level, int initial_level) : dim_(dim), max_level_(max_level) {
  if (dim < 1 || dim > 3) throw std::invalid_argument("acorn: input_dim = " + std::to_string(dim) + ": must be 1, 2 or 3");
  if (max_level < 0 || max_level > max_tree_level(dim))
    throw std::invalid_argument("field.max_level = " + std::to_string(max_level) + ": must be in [0, " +
                                std::to_string(max_tree_level(dim)) + "] for " + std::to_string(dim) + " inputs");
  if (initial_level < 0 || initial_level > max_level)
    throw std::invalid_argument("field.initial_level = " + std::to_string(initial_level) +
                                ": must be in [0, max_level = " + std::to_string(max_level) + "]");
  const int n = 1 << initial_level;
  const int count = 1 << (dim * initial_level);
  std::vector<Block> blocks(static_cast<size_t>(count));
  for (int k = 0; k < count; ++k) {
    Block& b = blocks[static_cast<size_t>(k)];
    b.level = initial_level;
    int rest = k;
    for (int j = 0; j < dim; ++j, rest /= n) b.index[static_cast<size_t>(j)] = rest % n;
  }
  set_blocks(std::move(blocks));
}

int BlockTree::active() const {
  int n = 0;
  for (const Block& b : blocks_) n += b.frozen ? 0 : 1;
  return n;
}

double BlockTree::size(int b) const { return std::ldexp(1.0, -blocks_[static_cast<size_t>(b)].level); }

double BlockTree::lower(int b, int axis) const {
  const Block& k = blocks_[static_cast<size_t>(b)];
  return std::ldexp(static_cast<double>(k.index[static_cast<size_t>(axis)]), -k.level);
}

double BlockTree::volume(int b) const { return std::ldexp(1.0, -dim_ * blocks_[static_cast<size_t>(b)].level); }

void BlockTree::set_blocks(std::vector<Block> blocks) {
  for (const Block& b : blocks) {
    if (b.level < 0 || b.level > max_level_)
      throw std::invalid_argument("acorn block tree: a block at level " + std::to_string(b.level) +
                                  ", outside [0, max_level = " + std::to_string(max_level_) + "]");
    for (int j = 0; j < dim_; ++j)
      if (b.index[static_cast<size_t>(j)] < 0 || b.index[static_cast<size_t>(j)] >= (1 << b.level))
        throw std::invalid_argument("acorn block tree: block index " + std::to_string(b.index[static_cast<size_t>(j)]) +
                                    " outside its level " + std::to_string(b.level));
  }
  lookup_ = lookup_of(blocks);
  blocks_ = std::move(blocks);
  ++version_;
}

std::vector<std::int32_t> BlockTree::lookup_of(const std::vector<Block>& blocks) const {
  const int cells = 1 << max_level_;
  std::int64_t total = 1;
  for (int j = 0; j < dim_; ++j) total *= cells;
  std::vector<std::int32_t> lookup(static_cast<size_t>(total), -1);
  for (size_t b = 0; b < blocks.size(); ++b) {
    const Block& k = blocks[b];
    const int span = 1 << (max_level_ - k.level);  // finest cells per block edge
    std::int64_t count = 1;
    for (int j = 0; j < dim_; ++j) count *= span;
    for (std::int64_t c = 0; c < count; ++c) {
      std::int64_t rest = c, cell = 0, stride = 1;
      for (int j = 0; j < dim_; ++j, rest /= span, stride *= cells)
        cell += (k.index[static_cast<size_t>(j)] * static_cast<std::int64_t>(span) + rest % span) * stride;
      std::int32_t& slot = lookup[static_cast<size_t>(cell)];
      if (slot >= 0) throw std::invalid_argument("acorn block tree: blocks overlap");
      slot = static_cast<std::int32_t>(b);
    }
  }
  for (std::int32_t slot : lookup)
    if (slot < 0) throw std::invalid_argument("acorn block tree: the blocks leave a gap");
  return lookup;
}

}  // namespace nfield::fields
