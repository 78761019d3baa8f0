// SPDX-License-Identifier: MIT
//
// `field.type: acorn` (fields/acorn.h): its keys, checkpoint attributes and block tree.
//
//   field:
//     type: acorn
//     hidden: [64]              # the decoder's hidden widths (feature grid → value)
//     activation: relu          # the decoder's activation (relu by default)
//     features: 8               # C, channels of each block's feature grid
//     grid: 16                  # G, grid vertices per axis of a block
//     encoder_hidden: [64, 64]  # the coordinate encoder's ReLU layers
//     encoder_octaves: 6        # positional encoding of the block centre and level
//     initial_level: 2          # the starting tiling (2^(d·level) blocks)
//     max_level: 6              # the finest level a split may reach
//     max_blocks: 256           # the budget of blocks the allocation keeps to
//     allocate_every: 100       # steps between allocations (0: the tree stays)
//     split_factor: 0.25        # β: a split block's error is β times its own (acorn_allocation.h)
//     freeze_below: 0           # a block whose mean squared error is below this freezes
//
// Checkpoints keep the options as acorn_* attributes and the tree as acorn_block_level,
// acorn_block_index (d per block), acorn_block_frozen and acorn_block_error, one entry per
// leaf in the tree's order, and the grids frozen blocks keep as the dataset acorn_kept_grids
// (C · G^d × k, a column per such block) with their indices in the attribute acorn_kept_blocks,
// so a resumed run and `nfield eval` see the same blocks.
#include <any>
#include <cmath>
#include <string>
#include <vector>
#include <span>
#include <stdexcept>

#include "fields/acorn.h"
#include "fields/activation_layer.h"
#include "fields/dense.h"
#include "fields/field_type.h"
#include "io/text.h"

namespace nfield::fields {
namespace {

class AcornType final : public FieldTypeOf<AcornType> {
 public:
  std::string default_activation() const override { return "relu"; }
  std::string refused_streams(const autodiff::StreamSpec& spec) const override {
    if (spec.operators.empty() && spec.taylor_order == 0) return {};
    return "gives the value and gradient (tangent) streams only; operator and Taylor streams "
           "(second and higher derivatives) are not provided (fields/acorn.h)";
  }
  void validate(const FieldOptions& o) const override {
    if (io::to_lower(o.encoding.type) != "identity")
      throw std::invalid_argument("field.encoding.type = " + o.encoding.type +
                                  ": acorn encodes the coordinates itself (its blocks); use identity");
    acorn_options(o).validate(o.input_dim);
  }
  template <typename Scalar>
  static FeatureEncoding<Scalar>* append(const FieldOptions& o, autodiff::Sequential<Scalar>& network) {
    network.add(std::make_unique<AcornEncoding<Scalar>>(o));
    Eigen::Index width = acorn_options(o).features;
    for (int h : o.hidden) {
      network.add(std::make_unique<Dense<Scalar>>(width, h));
      network.add(std::make_unique<ActivationLayer<Scalar>>(ActivationSpec{o.activation, o.hidden_omega}, h));
      width = h;
    }
    network.add(std::make_unique<Dense<Scalar>>(width, o.output_dim));
    return nullptr;
  }

  void read(const io::ConfigNode& node, FieldOptions& o) const override {
    AcornOptions a;
    if (node.has("features")) a.features = node.get_in_range("features", 1, 256);
    if (node.has("grid")) a.grid = node.get_in_range("grid", 2, 256);
    if (node.has("encoder_hidden")) {
      a.encoder_hidden = node.get<std::vector<int>>("encoder_hidden");
      node.require("encoder_hidden", !a.encoder_hidden.empty(), "expected a non-empty list of widths");
      for (int h : a.encoder_hidden)
        node.require("encoder_hidden", h >= 1 && h <= 4096, "expected widths in [1, 4096]");
    }
    if (node.has("encoder_octaves")) a.encoder_octaves = node.get_in_range("encoder_octaves", 0, 16);
    const int d = o.input_dim;
    node.require("type", d >= 1 && d <= 3, "acorn takes 1, 2 or 3 inputs, the problem gives " + std::to_string(d));
    if (node.has("max_level")) a.max_level = node.get_in_range("max_level", 0, max_tree_level(d));
    a.max_level = std::min(a.max_level, max_tree_level(d));
    if (node.has("initial_level")) a.initial_level = node.get_in_range("initial_level", 0, a.max_level);
    node.require("max_level", a.initial_level <= a.max_level,
                 "expected max_level >= initial_level = " + std::to_string(a.initial_level));
    const int initial = 1 << (d * a.initial_level);
    if (node.has("max_blocks")) a.max_blocks = node.get_in_range("max_blocks", 1, 4096);
    node.require("max_blocks", a.max_blocks >= initial,
                 "expected a budget of at least the " + std::to_string(initial) + " blocks of initial_level");
    if (node.has("allocate_every")) a.allocate_every = node.get_in_range("allocate_every", 0, 1 << 30);
    a.split_factor = node.get_or("split_factor", a.split_factor);
    node.require("split_factor", a.split_factor > 0 && a.split_factor < 1, "expected a number in (0, 1)");
    a.freeze_below = node.get_or("freeze_below", a.freeze_below);
    node.require("freeze_below", a.freeze_below >= 0 && std::isfinite(a.freeze_below),
                 "expected a finite number >= 0");
    double grid_size = a.features;
    for (int j = 0; j < d; ++j) grid_size *= a.grid;
    node.require("grid", grid_size <= (1 << 20), "expected features · grid^d <= 2^20 numbers per block");
    a.tree = std::make_shared<BlockTree>(d, a.max_level, a.initial_level);
    o.extension = a;
  }
  void write(const FieldOptions& o, YAML::Node& n) const override {
    const AcornOptions& a = acorn_options(o);
    n["features"] = a.features;
    n["grid"] = a.grid;
    n["encoder_hidden"] = a.encoder_hidden;
    n["encoder_octaves"] = a.encoder_octaves;
    n["initial_level"] = a.initial_level;
    n["max_level"] = a.max_level;
    n["max_blocks"] = a.max_blocks;
    n["allocate_every"] = a.allocate_every;
    n["split_factor"] = io::yaml_number(a.split_factor);
    n["freeze_below"] = io::yaml_number(a.freeze_below);
  }
  void save(io::H5Writer& file, const std::string& group, const FieldOptions& o) const override {
    const AcornOptions& a = acorn_options(o);
    const std::vector<std::int64_t> encoder(a.encoder_hidden.begin(), a.encoder_hidden.end());
    file.write_attribute(group, "acorn_features", a.features);
    file.write_attribute(group, "acorn_grid", a.grid);
    file.write_attribute(group, "acorn_encoder_hidden", std::span<const std::int64_t>(encoder));
    file.write_attribute(group, "acorn_encoder_octaves", a.encoder_octaves);
    file.write_attribute(group, "acorn_initial_level", a.initial_level);
    file.write_attribute(group, "acorn_max_level", a.max_level);
    file.write_attribute(group, "acorn_max_blocks", a.max_blocks);
    file.write_attribute(group, "acorn_allocate_every", a.allocate_every);
    file.write_attribute(group, "acorn_split_factor", a.split_factor);
    file.write_attribute(group, "acorn_freeze_below", a.freeze_below);
    if (!a.tree) return;
    std::vector<std::int64_t> level, index, frozen;
    std::vector<double> error;
    for (const Block& b : a.tree->blocks()) {
      level.push_back(b.level);
      for (int j = 0; j < a.tree->dim(); ++j) index.push_back(b.index[static_cast<size_t>(j)]);
      frozen.push_back(b.frozen ? 1 : 0);
      error.push_back(b.error);
    }
    file.write_attribute(group, "acorn_block_level", std::span<const std::int64_t>(level));
    file.write_attribute(group, "acorn_block_index", std::span<const std::int64_t>(index));
    file.write_attribute(group, "acorn_block_frozen", std::span<const std::int64_t>(frozen));
    file.write_attribute(group, "acorn_block_error", std::span<const double>(error));
    // The kept grids of frozen blocks (fields::Block::grid), one column each in the tree's order.
    std::vector<std::int64_t> kept;
    for (size_t b = 0; b < a.tree->blocks().size(); ++b)
      if (!a.tree->blocks()[b].grid.empty()) kept.push_back(static_cast<std::int64_t>(b));
    if (kept.empty()) return;
    const auto rows = static_cast<Eigen::Index>(a.tree->blocks()[static_cast<size_t>(kept[0])].grid.size());
    Eigen::MatrixXd grids(rows, static_cast<Eigen::Index>(kept.size()));
    for (size_t k = 0; k < kept.size(); ++k) {
      const std::vector<double>& g = a.tree->blocks()[static_cast<size_t>(kept[k])].grid;
      grids.col(static_cast<Eigen::Index>(k)) = Eigen::Map<const Eigen::VectorXd>(g.data(), rows);
    }
    file.write(group + "/acorn_kept_grids", grids);
    file.write_attribute(group, "acorn_kept_blocks", std::span<const std::int64_t>(kept));
  }
  void load(const io::H5Reader& file, const std::string& group, FieldOptions& o) const override {
    AcornOptions a;
    auto integer = [&](const char* name) { return static_cast<int>(file.read_attribute<std::int64_t>(group, name)); };
    a.features = integer("acorn_features");
    a.grid = integer("acorn_grid");
    const auto encoder = file.read_attribute<std::vector<std::int64_t>>(group, "acorn_encoder_hidden");
    a.encoder_hidden.assign(encoder.begin(), encoder.end());
    a.encoder_octaves = integer("acorn_encoder_octaves");
    a.initial_level = integer("acorn_initial_level");
    a.max_level = integer("acorn_max_level");
    a.max_blocks = integer("acorn_max_blocks");
    a.allocate_every = integer("acorn_allocate_every");
    a.split_factor = file.read_attribute<double>(group, "acorn_split_factor");
    a.freeze_below = file.read_attribute<double>(group, "acorn_freeze_below");
    a.tree = std::make_shared<BlockTree>(o.input_dim, a.max_level, a.initial_level);
    if (file.has_attribute(group, "acorn_block_level")) {
      const auto level = file.read_attribute<std::vector<std::int64_t>>(group, "acorn_block_level");
      const auto index = file.read_attribute<std::vector<std::int64_t>>(group, "acorn_block_index");
      const auto frozen = file.read_attribute<std::vector<std::int64_t>>(group, "acorn_block_frozen");
      const auto error = file.read_attribute<std::vector<double>>(group, "acorn_block_error");
      const size_t d = static_cast<size_t>(o.input_dim);
      if (index.size() != level.size() * d || frozen.size() != level.size() || error.size() != level.size())
        throw io::H5Error(file.path().string() + ": " + group + ": acorn_block_* attributes of different lengths");
      std::vector<Block> blocks(level.size());
      for (size_t b = 0; b < level.size(); ++b) {
        blocks[b].level = static_cast<int>(level[b]);
        for (size_t j = 0; j < d; ++j) blocks[b].index[j] = static_cast<int>(index[b * d + j]);
        blocks[b].frozen = frozen[b] != 0;
        blocks[b].error = error[b];
      }
      if (file.has_attribute(group, "acorn_kept_blocks")) {
        const auto kept = file.read_attribute<std::vector<std::int64_t>>(group, "acorn_kept_blocks");
        const Eigen::MatrixXd grids = file.read_matrix<double>(group + "/acorn_kept_grids");
        const Eigen::Index rows = static_cast<Eigen::Index>(a.features) *
                                  static_cast<Eigen::Index>(std::pow(a.grid, o.input_dim));
        if (grids.cols() != static_cast<Eigen::Index>(kept.size()) || grids.rows() != rows)
          throw io::H5Error(file.path().string() + ": " + group + ": acorn_kept_grids is " +
                            std::to_string(grids.rows()) + " x " + std::to_string(grids.cols()) + ", expected " +
                            std::to_string(rows) + " x " + std::to_string(kept.size()));
        for (size_t k = 0; k < kept.size(); ++k) {
          const auto b = static_cast<size_t>(kept[k]);
          if (kept[k] < 0 || b >= blocks.size() || !blocks[b].frozen)
            throw io::H5Error(file.path().string() + ": " + group + ": acorn_kept_blocks names block " +
                              std::to_string(kept[k]) + ", not a frozen block of the tree");
          const auto column = grids.col(static_cast<Eigen::Index>(k));
          blocks[b].grid.assign(column.data(), column.data() + rows);
        }
      }
      try {
        a.tree->set_blocks(std::move(blocks));
      } catch (const std::invalid_argument& e) {
        throw io::H5Error(file.path().string() + ": " + group + ": " + e.what());
      }
    }
    o.extension = a;
  }
};

}  // namespace

std::unique_ptr<const FieldType> make_acorn_type() { return std::make_unique<AcornType>(); }

}  // namespace nfield::fields
