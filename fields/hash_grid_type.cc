// SPDX-License-Identifier: MIT
//
// The registry entry of `hash_grid` (fields/encoding_type.h): its options, config keys and
// checkpoint attributes. The module is fields/hash_grid.h.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fields/encoding_type.h"
#include "fields/hash_grid.h"
#include "io/text.h"

namespace nfield::fields {
namespace {

constexpr int kMaxDim = 4;
constexpr int kMaxLevels = 32;
constexpr int kMaxFeatures = 16;
constexpr int kMinLog2Table = 10, kMaxLog2Table = 24;
// Cell indices stay far inside 32 bits, and a float still resolves a cell of the finest level.
constexpr int kMaxResolution = 1 << 20;

[[noreturn]] void reject(const std::string& option, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument("encoding." + option + " = " + value + ": " + rule);
}

void check_range(const std::string& option, int value, int lowest, int highest) {
  if (value < lowest || value > highest)
    reject(option, std::to_string(value),
           "must be in [" + std::to_string(lowest) + ", " + std::to_string(highest) + "]");
}

const std::vector<std::string>& interpolations() {
  static const std::vector<std::string> names{"linear", "smoothstep", "cubic"};
  return names;
}

}  // namespace

void HashGridOptions::validate() const {
  check_range("levels", levels, 1, kMaxLevels);
  check_range("features_per_level", features_per_level, 1, kMaxFeatures);
  check_range("log2_table_size", log2_table_size, kMinLog2Table, kMaxLog2Table);
  check_range("base_resolution", base_resolution, 1, kMaxResolution);
  check_range("finest_resolution", finest_resolution, base_resolution, kMaxResolution);
  if (!(init_scale > 0) || !std::isfinite(init_scale))
    reject("init_scale", std::to_string(init_scale), "must be a finite number > 0");
  const std::string kind = io::to_lower(interpolation);
  if (std::find(interpolations().begin(), interpolations().end(), kind) == interpolations().end())
    reject("interpolation", "'" + interpolation + "'", "must be linear, smoothstep or cubic");
}

namespace {

class HashGridType final : public EncodingTypeOf<HashGridType, HashGridOptions> {
 public:
  void validate(const EncodingOptions& o) const override { own(o).validate(); }
  void validate_inputs(const EncodingOptions&, int input_dim) const override {
    if (input_dim < 1 || input_dim > kMaxDim)
      reject("type", "hash_grid", "takes 1 to 4 inputs, not " + std::to_string(input_dim));
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    return std::make_unique<HashGridEncoding<Scalar>>(o, input_dim);
  }
  void read(const io::ConfigNode& e, const EncodingContext&, EncodingOptions& o) const override {
    HashGridOptions h;
    if (e.has("levels")) h.levels = e.get_in_range("levels", 1, kMaxLevels);
    if (e.has("features_per_level"))
      h.features_per_level = e.get_in_range("features_per_level", 1, kMaxFeatures);
    if (e.has("log2_table_size"))
      h.log2_table_size = e.get_in_range("log2_table_size", kMinLog2Table, kMaxLog2Table);
    if (e.has("base_resolution"))
      h.base_resolution = e.get_in_range("base_resolution", 1, kMaxResolution);
    if (e.has("finest_resolution"))
      h.finest_resolution = e.get_in_range("finest_resolution", 1, kMaxResolution);
    e.require("finest_resolution", h.finest_resolution >= h.base_resolution,
              "expected a number >= base_resolution = " + std::to_string(h.base_resolution));
    h.interpolation = e.get_choice("interpolation", interpolations(), "linear");
    h.include_input = e.get_or("include_input", true);
    h.init_scale = e.get_or("init_scale", h.init_scale);
    e.require("init_scale", h.init_scale > 0 && std::isfinite(h.init_scale),
              "expected a finite number > 0");
    o.own = h;
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    const HashGridOptions& h = own(o);
    n["levels"] = h.levels;
    n["features_per_level"] = h.features_per_level;
    n["log2_table_size"] = h.log2_table_size;
    n["base_resolution"] = h.base_resolution;
    n["finest_resolution"] = h.finest_resolution;
    n["interpolation"] = io::to_lower(h.interpolation);
    n["include_input"] = h.include_input;
    n["init_scale"] = io::yaml_number(h.init_scale);
  }
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    const HashGridOptions& h = own(o);
    file.write_attribute(group, "encoding_levels", h.levels);
    file.write_attribute(group, "encoding_features_per_level", h.features_per_level);
    file.write_attribute(group, "encoding_log2_table_size", h.log2_table_size);
    file.write_attribute(group, "encoding_base_resolution", h.base_resolution);
    file.write_attribute(group, "encoding_finest_resolution", h.finest_resolution);
    file.write_attribute(group, "encoding_interpolation", io::to_lower(h.interpolation));
    file.write_attribute(group, "encoding_include_input", static_cast<std::int64_t>(h.include_input));
    file.write_attribute(group, "encoding_init_scale", h.init_scale);
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    HashGridOptions h;
    auto integer = [&](const char* name) {
      return static_cast<int>(file.read_attribute<std::int64_t>(group, name));
    };
    h.levels = integer("encoding_levels");
    h.features_per_level = integer("encoding_features_per_level");
    h.log2_table_size = integer("encoding_log2_table_size");
    h.base_resolution = integer("encoding_base_resolution");
    h.finest_resolution = integer("encoding_finest_resolution");
    h.interpolation = file.read_attribute<std::string>(group, "encoding_interpolation");
    if (file.has_attribute(group, "encoding_include_input"))
      h.include_input = integer("encoding_include_input") != 0;
    h.init_scale = file.read_attribute<double>(group, "encoding_init_scale");
    o.own = h;
  }
};

}  // namespace

std::unique_ptr<const EncodingType> make_hash_grid_type() { return std::make_unique<HashGridType>(); }

}  // namespace nfield::fields
