// SPDX-License-Identifier: MIT
#include "fields/acorn_allocation.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>

namespace nfield::fields {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The parent of a block at level > 0, as a sortable key.
std::array<int, 4> parent_key(const Block& b) {
  return {b.level - 1, b.index[0] >> 1, b.index[1] >> 1, b.index[2] >> 1};
}

// One item of the knapsack: its members (leaf indices) and, per block count, the cheapest
// option: its cost and its choices (a member bit set: split; merge: all members kMerge).
struct Option {
  int count = 0;
  double cost = kInfinity;
  std::uint32_t splits = 0;
  bool merge = false;
};
struct Item {
  std::vector<int> members;
  std::vector<Option> options;  // the cheapest per count, counts increasing
};

// The complete sibling groups of active leaves: parent → members, only those with all
// 2^d children present, none frozen.
std::map<std::array<int, 4>, std::vector<int>> complete_groups(const std::vector<Block>& blocks, int dim) {
  std::map<std::array<int, 4>, std::vector<int>> groups;
  for (size_t i = 0; i < blocks.size(); ++i)
    if (blocks[i].level > 0) groups[parent_key(blocks[i])].push_back(static_cast<int>(i));
  std::erase_if(groups, [&](const auto& g) {
    if (static_cast<int>(g.second.size()) != (1 << dim)) return true;
    return std::any_of(g.second.begin(), g.second.end(), [&](int i) { return blocks[static_cast<size_t>(i)].frozen; });
  });
  return groups;
}

Item make_item(const std::vector<Block>& blocks, std::vector<int> members, bool can_merge, int dim,
               int max_level, double beta) {
  Item item;
  item.members = std::move(members);
  const int m = static_cast<int>(item.members.size()), children = 1 << dim;
  std::map<int, Option> best;
  auto offer = [&](const Option& o) {
    auto [it, inserted] = best.try_emplace(o.count, o);
    if (!inserted && o.cost < it->second.cost) it->second = o;
  };
  double sum = 0;
  for (int i : item.members) sum += blocks[static_cast<size_t>(i)].error;
  if (can_merge) offer({1, sum / beta, 0, true});
  for (std::uint32_t mask = 0; mask < (1u << m); ++mask) {
    Option o{0, 0, mask, false};
    for (int k = 0; k < m; ++k) {
      const Block& b = blocks[static_cast<size_t>(item.members[static_cast<size_t>(k)])];
      const bool split = (mask >> k) & 1u;
      if (split && (b.frozen || b.level >= max_level)) {
        o.cost = kInfinity;
        break;
      }
      o.count += split ? children : 1;
      o.cost += split ? beta * b.error : b.error;
    }
    if (o.cost < kInfinity) offer(o);
  }
  for (const auto& [count, o] : best) item.options.push_back(o);
  return item;
}

}  // namespace

Allocation allocate_blocks(const std::vector<Block>& blocks, int dim, int max_level, int budget,
                           double beta) {
  if (budget < 1) throw std::invalid_argument("acorn allocation: budget must be >= 1");
  if (!(beta > 0 && beta < 1)) throw std::invalid_argument("acorn allocation: split_factor must be in (0, 1)");
  // Items in tree order: a group where its first member stands.
  const auto groups = complete_groups(blocks, dim);
  std::vector<int> group_of(blocks.size(), -1);
  std::vector<std::vector<int>> group_members;
  for (const auto& [key, members] : groups) {
    for (int i : members) group_of[static_cast<size_t>(i)] = static_cast<int>(group_members.size());
    group_members.push_back(members);
  }
  std::vector<Item> items;
  std::vector<bool> placed(group_members.size(), false);
  for (size_t i = 0; i < blocks.size(); ++i) {
    const int g = group_of[i];
    if (g < 0) {
      items.push_back(make_item(blocks, {static_cast<int>(i)}, false, dim, max_level, beta));
    } else if (!placed[static_cast<size_t>(g)]) {
      placed[static_cast<size_t>(g)] = true;
      items.push_back(make_item(blocks, group_members[static_cast<size_t>(g)], true, dim, max_level, beta));
    }
  }
  // The program's capacity: the budget, or the fewest blocks possible if that is more.
  int fewest = 0;
  for (const Item& item : items) fewest += item.options.front().count;
  const int cap = std::max(budget, fewest);
  const size_t width = static_cast<size_t>(cap) + 1;
  std::vector<double> d(width, kInfinity), next(width);
  d[0] = 0;
  std::vector<std::vector<std::uint8_t>> pick(items.size(), std::vector<std::uint8_t>(width, 0));
  for (size_t k = 0; k < items.size(); ++k) {
    std::fill(next.begin(), next.end(), kInfinity);
    const auto& options = items[k].options;
    for (size_t c = 0; c < width; ++c)
      for (size_t o = 0; o < options.size(); ++o) {
        const auto n = static_cast<size_t>(options[o].count);
        if (n > c || d[c - n] == kInfinity) continue;
        const double value = d[c - n] + options[o].cost;
        if (value < next[c]) {
          next[c] = value;
          pick[k][c] = static_cast<std::uint8_t>(o);
        }
      }
    std::swap(d, next);
  }
  size_t best = 0;
  for (size_t c = 1; c < width; ++c)
    if (d[c] < d[best]) best = c;  // strict: the fewer blocks on ties
  Allocation a;
  a.cost = d[best];
  a.blocks = static_cast<int>(best);
  a.choices.assign(blocks.size(), BlockChoice::kKeep);
  for (size_t k = items.size(); k-- > 0;) {
    const Option& o = items[k].options[pick[k][best]];
    for (size_t m = 0; m < items[k].members.size(); ++m)
      a.choices[static_cast<size_t>(items[k].members[m])] =
          o.merge ? BlockChoice::kMerge : ((o.splits >> m) & 1u) ? BlockChoice::kSplit : BlockChoice::kKeep;
    best -= static_cast<size_t>(o.count);
  }
  return a;
}

Allocation evaluate_allocation(const std::vector<Block>& blocks, int dim, int max_level, double beta,
                               std::vector<BlockChoice> choices) {
  Allocation a;
  const auto groups = complete_groups(blocks, dim);
  std::map<std::array<int, 4>, int> merging;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const Block& b = blocks[i];
    switch (choices[i]) {
      case BlockChoice::kKeep:
        a.blocks += 1;
        a.cost += b.error;
        break;
      case BlockChoice::kSplit:
        if (b.frozen || b.level >= max_level) a.cost = kInfinity;
        a.blocks += 1 << dim;
        a.cost += beta * b.error;
        break;
      case BlockChoice::kMerge:
        if (b.level == 0 || !groups.count(parent_key(b))) a.cost = kInfinity;
        else ++merging[parent_key(b)];
        a.cost += b.error / beta;
        break;
    }
  }
  for (const auto& [key, count] : merging) {
    if (count != (1 << dim)) a.cost = kInfinity;
    a.blocks += 1;
  }
  a.choices = std::move(choices);
  return a;
}

std::vector<Block> apply_allocation(const std::vector<Block>& blocks, int dim,
                                    const std::vector<BlockChoice>& choices) {
  std::vector<Block> kept, children;
  std::map<std::array<int, 4>, Block> parents;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const Block& b = blocks[i];
    if (choices[i] == BlockChoice::kKeep) {
      kept.push_back(b);
    } else if (choices[i] == BlockChoice::kSplit) {
      for (int c = 0; c < (1 << dim); ++c) {
        Block child;
        child.level = b.level + 1;
        for (int j = 0; j < dim; ++j)
          child.index[static_cast<size_t>(j)] = 2 * b.index[static_cast<size_t>(j)] + ((c >> j) & 1);
        children.push_back(child);
      }
    } else {
      const auto key = parent_key(b);
      Block parent;
      parent.level = key[0];
      for (int j = 0; j < dim; ++j) parent.index[static_cast<size_t>(j)] = key[static_cast<size_t>(j) + 1];
      parents.emplace(key, parent);
    }
  }
  kept.insert(kept.end(), children.begin(), children.end());
  for (const auto& [key, parent] : parents) kept.push_back(parent);
  return kept;
}

}  // namespace nfield::fields
