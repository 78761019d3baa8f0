// SPDX-License-Identifier: MIT
//
// Where an adaptive field's budget went: the leaves of an acorn field's block tree
// (fields/acorn_tree.h) as `blocks.vtp` in the run's folder, in the field's coordinates
// (encoding.lower/upper): per block a filled rectangle (2-D: two triangles; 3-D: the box's
// twelve triangles; 1-D: a segment) and its outline (line cells), with the point arrays
// `level`, `error` (the allocation's last estimate, fields/acorn_allocation.h) and `frozen`
// (0 or 1), constant over each block's own corner points. In ParaView colour by `level` or
// `error`, the outline drawn over the fitted picture.
#pragma once

#include <filesystem>

#include "fields/acorn_tree.h"
#include "fields/field_options.h"
#include "io/poly_data.h"

namespace nfield::solvers {

// The blocks of `tree` over the box [lower, upper] (lower/upper: tree.dim() values each).
io::PolyData block_poly_data(const fields::BlockTree& tree, const std::vector<double>& lower,
                             const std::vector<double>& upper);

// Writes dir/blocks.vtp for an acorn field; nothing for any other field.
void write_block_outputs(const fields::FieldOptions& field, const std::filesystem::path& dir);

}  // namespace nfield::solvers
