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

class HashGridType final : public EncodingTypeOf<HashGridType> {
 public:
  void validate(const EncodingOptions& o) const override {
    check_range("levels", o.levels, 1, kMaxLevels);
    check_range("features_per_level", o.features_per_level, 1, kMaxFeatures);
    check_range("log2_table_size", o.log2_table_size, kMinLog2Table, kMaxLog2Table);
    check_range("base_resolution", o.base_resolution, 1, kMaxResolution);
    check_range("finest_resolution", o.finest_resolution, o.base_resolution, kMaxResolution);
    if (!(o.init_scale > 0) || !std::isfinite(o.init_scale))
      reject("init_scale", std::to_string(o.init_scale), "must be a finite number > 0");
    const std::string kind = io::to_lower(o.interpolation);
    if (std::find(interpolations().begin(), interpolations().end(), kind) == interpolations().end())
      reject("interpolation", "'" + o.interpolation + "'", "must be linear, smoothstep or cubic");
  }
  void validate_inputs(const EncodingOptions&, int input_dim) const override {
    if (input_dim < 1 || input_dim > kMaxDim)
      reject("type", "hash_grid", "takes 1 to 4 inputs, not " + std::to_string(input_dim));
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    return std::make_unique<HashGridEncoding<Scalar>>(o, input_dim);
  }
  void read(const io::ConfigNode& e, const EncodingContext&, EncodingOptions& o) const override {
    if (e.has("levels")) o.levels = e.get_in_range("levels", 1, kMaxLevels);
    if (e.has("features_per_level"))
      o.features_per_level = e.get_in_range("features_per_level", 1, kMaxFeatures);
    if (e.has("log2_table_size"))
      o.log2_table_size = e.get_in_range("log2_table_size", kMinLog2Table, kMaxLog2Table);
    if (e.has("base_resolution"))
      o.base_resolution = e.get_in_range("base_resolution", 1, kMaxResolution);
    if (e.has("finest_resolution"))
      o.finest_resolution = e.get_in_range("finest_resolution", 1, kMaxResolution);
    e.require("finest_resolution", o.finest_resolution >= o.base_resolution,
              "expected a number >= base_resolution = " + std::to_string(o.base_resolution));
    o.interpolation = e.get_choice("interpolation", interpolations(), "linear");
    o.include_input = e.get_or("include_input", true);
    o.init_scale = e.get_or("init_scale", o.init_scale);
    e.require("init_scale", o.init_scale > 0 && std::isfinite(o.init_scale),
              "expected a finite number > 0");
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    n["levels"] = o.levels;
    n["features_per_level"] = o.features_per_level;
    n["log2_table_size"] = o.log2_table_size;
    n["base_resolution"] = o.base_resolution;
    n["finest_resolution"] = o.finest_resolution;
    n["interpolation"] = io::to_lower(o.interpolation);
    n["include_input"] = o.include_input;
    n["init_scale"] = io::yaml_number(o.init_scale);
  }
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    file.write_attribute(group, "encoding_levels", o.levels);
    file.write_attribute(group, "encoding_features_per_level", o.features_per_level);
    file.write_attribute(group, "encoding_log2_table_size", o.log2_table_size);
    file.write_attribute(group, "encoding_base_resolution", o.base_resolution);
    file.write_attribute(group, "encoding_finest_resolution", o.finest_resolution);
    file.write_attribute(group, "encoding_interpolation", io::to_lower(o.interpolation));
    file.write_attribute(group, "encoding_init_scale", o.init_scale);
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    auto integer = [&](const char* name) {
      return static_cast<int>(file.read_attribute<std::int64_t>(group, name));
    };
    o.levels = integer("encoding_levels");
    o.features_per_level = integer("encoding_features_per_level");
    o.log2_table_size = integer("encoding_log2_table_size");
    o.base_resolution = integer("encoding_base_resolution");
    o.finest_resolution = integer("encoding_finest_resolution");
    o.interpolation = file.read_attribute<std::string>(group, "encoding_interpolation");
    o.init_scale = file.read_attribute<double>(group, "encoding_init_scale");
  }
};

}  // namespace

std::unique_ptr<const EncodingType> make_hash_grid_type() { return std::make_unique<HashGridType>(); }

}  // namespace nfield::fields
