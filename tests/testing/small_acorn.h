// SPDX-License-Identifier: MIT
//
// The small ACORN the tests share (tests/fields/acorn_test.cc, the stream harness in
// tests/testing/stream_checks.h): a grid of 4 vertices an axis with 3 features, a 5-wide
// encoder of 2 octaves, blocks from level 1 to 3, and a tree split once more in one corner.
#pragma once

#include <vector>

#include "fields/acorn.h"
#include "fields/acorn_tree.h"

namespace nfield::testutil {

inline fields::AcornOptions small_acorn_options() {
  fields::AcornOptions a;
  a.features = 3;
  a.grid = 4;
  a.encoder_hidden = {5};
  a.encoder_octaves = 2;
  a.initial_level = 1;
  a.max_level = 3;
  a.max_blocks = 64;
  return a;
}

// The level-1 blocks of [0, 1)^dim but the last (all indices 1), and the 2^dim children of
// that one at level 2: two levels, one complete group at each.
inline std::vector<fields::Block> split_corner(int dim) {
  std::vector<fields::Block> blocks;
  const int corners = 1 << dim;
  for (int level : {1, 2})
    for (int i = 0; i < (level == 1 ? corners - 1 : corners); ++i) {
      fields::Block b{level, {0, 0, 0}};
      for (int j = 0; j < dim; ++j) b.index[j] = (level == 1 ? 0 : 2) + ((i >> j) & 1);
      blocks.push_back(b);
    }
  return blocks;
}

}  // namespace nfield::testutil
