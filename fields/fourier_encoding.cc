// SPDX-License-Identifier: MIT
#include "fields/fourier_encoding.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <string>

#include "fields/encoding_type.h"

namespace nfield::fields {
namespace {

[[noreturn]] void reject(const std::string& option, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument("encoding." + option + " = " + value + ": " + rule);
}

// Standard normal draws that do not depend on the standard library's distributions.
double normal(std::mt19937_64& rng) {
  const double u1 = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace

void FourierOptions::validate() const {
  if (features < 1) reject("features", std::to_string(features), "must be >= 1");
  if (!(scale > 0)) reject("scale", std::to_string(scale), "must be > 0");
  for (std::size_t g = 0; g < scales.size(); ++g)
    for (double v : scales[g])
      if (!(v > 0)) reject("scales[" + std::to_string(g) + "]", std::to_string(v), "every σ must be > 0");
}

void FourierOptions::validate(int input_dim) const {
  validate();
  for (std::size_t g = 0; g < scales.size(); ++g) {
    const auto n = static_cast<int>(scales[g].size());
    if (n != 1 && n != input_dim)
      reject("scales[" + std::to_string(g) + "]", std::to_string(n) + " values",
             "needs one σ for every axis or one per axis (" + std::to_string(input_dim) + ")");
  }
}

namespace {

// `scales` as a list of blocks, each a number or a list of one σ per axis.
std::vector<std::vector<double>> read_scales(const io::ConfigNode& e) {
  e.require("scales", e.has_list("scales") && e.child("scales").size() > 0,
            "expected a list of scales, each a number or a list of one σ per axis");
  if (e.has("scale")) throw e.error("scales", "give scale or scales, not both");
  const io::ConfigNode list = e.child("scales");
  std::vector<std::vector<double>> scales;
  for (std::size_t g = 0; g < list.size(); ++g) {
    const io::ConfigNode item = list.at(g);
    std::vector<double> block = item.is_sequence() ? item.as<std::vector<double>>()
                                                   : std::vector<double>{item.as<double>()};
    item.require(!block.empty() && std::all_of(block.begin(), block.end(), [](double v) { return v > 0; }),
                 "expected σ > 0, a number or one per axis");
    scales.push_back(std::move(block));
  }
  return scales;
}

class FourierType final : public EncodingTypeOf<FourierType, FourierOptions> {
 public:
  void validate(const EncodingOptions& o) const override { own(o).validate(); }
  void validate_inputs(const EncodingOptions& o, int input_dim) const override {
    own(o).validate(input_dim);
  }
  // The 2π of Fourier features is folded into B.
  Eigen::MatrixXd matrix(const EncodingOptions& o, int input_dim) const override {
    const FourierOptions& f = own(o);
    std::mt19937_64 rng(f.seed);
    const std::vector<std::vector<double>> scales =
        f.scales.empty() ? std::vector<std::vector<double>>{{f.scale}} : f.scales;
    Eigen::MatrixXd b(f.features * static_cast<Eigen::Index>(scales.size()), input_dim);
    for (Eigen::Index r = 0; r < b.rows(); ++r)
      for (Eigen::Index c = 0; c < b.cols(); ++c) {
        const std::vector<double>& block = scales[static_cast<std::size_t>(r / f.features)];
        b(r, c) = 2.0 * std::numbers::pi * block[block.size() == 1 ? 0 : static_cast<std::size_t>(c)] * normal(rng);
      }
    return b;
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    return make_sinusoids<Scalar>(FourierType().matrix(o, input_dim), false);
  }
  void read(const io::ConfigNode& e, const EncodingContext& context,
            EncodingOptions& o) const override {
    FourierOptions f;
    if (e.has("features")) f.features = e.get_in_range("features", 1, 65536);
    f.scale = e.get_or("scale", f.scale);
    e.require("scale", f.scale > 0, "expected a number > 0");
    if (e.has("scales")) f.scales = read_scales(e);
    f.seed = e.has("seed") ? static_cast<std::uint64_t>(e.get_nonnegative<std::int64_t>("seed"))
                           : context.seed;
    o.own = f;
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    const FourierOptions& f = own(o);
    n["features"] = f.features;
    if (f.scales.empty()) n["scale"] = f.scale;
    for (const std::vector<double>& block : f.scales) {
      YAML::Node item;
      for (double v : block) item.push_back(v);
      item.SetStyle(YAML::EmitterStyle::Flow);
      n["scales"].push_back(item);
    }
    n["seed"] = f.seed;
  }
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    const FourierOptions& f = own(o);
    file.write_attribute(group, "encoding_features", f.features);
    file.write_attribute(group, "encoding_scale", f.scale);
    file.write_attribute(group, "encoding_seed", static_cast<std::int64_t>(f.seed));
    if (f.scales.empty()) return;
    std::vector<double> values;
    std::vector<std::int64_t> sizes;
    for (const std::vector<double>& block : f.scales) {
      values.insert(values.end(), block.begin(), block.end());
      sizes.push_back(static_cast<std::int64_t>(block.size()));
    }
    file.write_attribute(group, "encoding_scales", std::span<const double>(values));
    file.write_attribute(group, "encoding_scales_sizes", std::span<const std::int64_t>(sizes));
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    FourierOptions f;
    if (file.has_attribute(group, "encoding_features"))
      f.features = static_cast<int>(file.read_attribute<std::int64_t>(group, "encoding_features"));
    if (file.has_attribute(group, "encoding_scale"))
      f.scale = file.read_attribute<double>(group, "encoding_scale");
    if (file.has_attribute(group, "encoding_seed"))
      f.seed = static_cast<std::uint64_t>(file.read_attribute<std::int64_t>(group, "encoding_seed"));
    if (file.has_attribute(group, "encoding_scales")) {
      const auto values = file.read_attribute<std::vector<double>>(group, "encoding_scales");
      const auto sizes = file.read_attribute<std::vector<std::int64_t>>(group, "encoding_scales_sizes");
      std::size_t at = 0;
      for (std::int64_t n : sizes) {
        if (n < 1 || at + static_cast<std::size_t>(n) > values.size())
          throw io::H5Error(file.path().string() + ": " + group + ": encoding_scales_sizes does not match encoding_scales");
        f.scales.emplace_back(values.begin() + static_cast<std::ptrdiff_t>(at), values.begin() + static_cast<std::ptrdiff_t>(at + n));
        at += static_cast<std::size_t>(n);
      }
    }
    o.own = f;
  }
};

}  // namespace

std::unique_ptr<const EncodingType> make_fourier_type() { return std::make_unique<FourierType>(); }

}  // namespace nfield::fields
