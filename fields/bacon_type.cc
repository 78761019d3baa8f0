// SPDX-License-Identifier: MIT
//
// `field.type: bacon` (fields/bacon.h): its keys, checkpoint attributes and scales.
//
//   field:
//     type: bacon
//     hidden: [256, 256, 256, 256, 256]   # widths of the filter layers 0 … L
//     resolution: [64, 128, 256]          # one scale each: the Nyquist limit of N samples an axis
//     max_frequency: [16, 32, 64]         # or: cut-offs in cycles per unit of the domain
//     output_layers: [2, 3, 4]            # the layer each scale reads (default: the last ones)
//     train_scales: all                   # all (sum of the scales' losses) | output
//     output_scale: -1                    # the scale problems and outputs see (-1: finest)
//     period: 1                           # the filters' period, in box widths
#include <any>
#include <span>
#include <stdexcept>

#include "fields/bacon.h"
#include "fields/field_type.h"
#include "io/text.h"

namespace nfield::fields {
namespace {

class BaconType final : public FieldTypeOf<BaconType> {
 public:
  std::string default_activation() const override { return "sine"; }
  bool has_activation() const override { return false; }
  void validate(const FieldOptions& o) const override {
    if (io::to_lower(o.encoding.type) != "identity")
      throw std::invalid_argument("field.encoding.type = " + o.encoding.type +
                                  ": bacon reads the coordinates itself (its filters); use identity");
    bacon_options(o).validate(static_cast<int>(o.hidden.size()));
  }
  template <typename Scalar>
  static FeatureEncoding<Scalar>* append(const FieldOptions& o, autodiff::Sequential<Scalar>& network) {
    network.add(std::make_unique<BaconNetwork<Scalar>>(o));
    return nullptr;
  }
  int output_scales(const FieldOptions& o) const override { return bacon_options(o).scales(); }
  int output_scale(const FieldOptions& o) const override { return bacon_options(o).chosen_scale(); }
  bool trains_all_scales(const FieldOptions& o) const override { return bacon_options(o).train_all_scales; }
  Eigen::MatrixXd scale_cutoffs(const FieldOptions& o) const override {
    const Eigen::VectorXd period = bacon_periods(o);
    Eigen::MatrixXd cutoffs = bacon_cutoff_steps(o).cast<double>();
    for (Eigen::Index k = 0; k < cutoffs.cols(); ++k) cutoffs.col(k) /= period(k);
    return cutoffs;
  }

  void read(const io::ConfigNode& node, FieldOptions& o) const override {
    BaconOptions b;
    b.resolution.clear();
    node.require("max_frequency", !(node.has("resolution") && node.has("max_frequency")),
                 "give either max_frequency or resolution, not both");
    if (node.has("max_frequency")) {
      b.max_frequency = node.get<std::vector<double>>("max_frequency");
      node.require("max_frequency", !b.max_frequency.empty(), "expected a list of cut-offs, one per scale");
      for (size_t s = 0; s < b.max_frequency.size(); ++s) {
        node.require("max_frequency", b.max_frequency[s] > 0 && b.max_frequency[s] <= 1e6,
                     "expected cut-offs in (0, 1e6] cycles per unit");
        node.require("max_frequency", s == 0 || b.max_frequency[s] > b.max_frequency[s - 1],
                     "expected cut-offs that increase from scale to scale");
      }
    } else {
      b.resolution = node.has("resolution") ? node.get<std::vector<int>>("resolution") : bacon_options({}).resolution;
      node.require("resolution", !b.resolution.empty(), "expected a list of resolutions, one per scale");
      for (size_t s = 0; s < b.resolution.size(); ++s) {
        node.require("resolution", b.resolution[s] >= 2 && b.resolution[s] <= (1 << 20),
                     "expected resolutions in [2, 1048576]");
        node.require("resolution", s == 0 || b.resolution[s] > b.resolution[s - 1],
                     "expected resolutions that increase from scale to scale");
      }
    }
    const int layers = static_cast<int>(o.hidden.size());
    node.require("hidden", layers >= b.scales(),
                 "bacon needs at least one layer per scale (" + std::to_string(b.scales()) + ")");
    if (node.has("output_layers")) {
      b.output_layers = node.get<std::vector<int>>("output_layers");
      try {
        b.validate(layers);
      } catch (const std::invalid_argument& e) {
        throw node.error("output_layers", e.what());
      }
    }
    b.train_all_scales = node.get_choice("train_scales", {"all", "output"}, "all") == "all";
    b.output_scale = node.has("output_scale") ? node.get_in_range("output_scale", -1, b.scales() - 1) : -1;
    b.period = node.has("period") ? node.get_in_range("period", 1, 64) : 1;
    o.extension = b;
  }
  void write(const FieldOptions& o, YAML::Node& n) const override {
    const BaconOptions& b = bacon_options(o);
    if (b.resolution.empty())
      n["max_frequency"] = b.max_frequency;
    else
      n["resolution"] = b.resolution;
    n["output_layers"] = b.head_layers(static_cast<int>(o.hidden.size()));
    n["train_scales"] = b.train_all_scales ? "all" : "output";
    n["output_scale"] = b.output_scale;
    n["period"] = b.period;
  }
  void save(io::H5Writer& file, const std::string& group, const FieldOptions& o) const override {
    const BaconOptions& b = bacon_options(o);
    const std::vector<std::int64_t> resolution(b.resolution.begin(), b.resolution.end());
    const std::vector<int> heads = b.head_layers(static_cast<int>(o.hidden.size()));
    const std::vector<std::int64_t> layers(heads.begin(), heads.end());
    if (!resolution.empty()) file.write_attribute(group, "bacon_resolution", std::span<const std::int64_t>(resolution));
    if (!b.max_frequency.empty())
      file.write_attribute(group, "bacon_max_frequency", std::span<const double>(b.max_frequency));
    file.write_attribute(group, "bacon_output_layers", std::span<const std::int64_t>(layers));
    file.write_attribute(group, "bacon_train_all_scales", static_cast<std::int64_t>(b.train_all_scales));
    file.write_attribute(group, "bacon_output_scale", static_cast<std::int64_t>(b.output_scale));
    file.write_attribute(group, "bacon_period", static_cast<std::int64_t>(b.period));
  }
  void load(const io::H5Reader& file, const std::string& group, FieldOptions& o) const override {
    BaconOptions b;
    if (file.has_attribute(group, "bacon_resolution")) {
      const auto r = file.read_attribute<std::vector<std::int64_t>>(group, "bacon_resolution");
      b.resolution.assign(r.begin(), r.end());
    } else {
      b.resolution.clear();
      b.max_frequency = file.read_attribute<std::vector<double>>(group, "bacon_max_frequency");
    }
    const auto layers = file.read_attribute<std::vector<std::int64_t>>(group, "bacon_output_layers");
    b.output_layers.assign(layers.begin(), layers.end());
    b.train_all_scales = file.read_attribute<std::int64_t>(group, "bacon_train_all_scales") != 0;
    b.output_scale = static_cast<int>(file.read_attribute<std::int64_t>(group, "bacon_output_scale"));
    b.period = static_cast<int>(file.read_attribute<std::int64_t>(group, "bacon_period"));
    o.extension = b;
  }
};

}  // namespace

std::unique_ptr<const FieldType> make_bacon_type() { return std::make_unique<BaconType>(); }

}  // namespace nfield::fields
