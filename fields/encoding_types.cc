// SPDX-License-Identifier: MIT
//
// The registered encoding types (fields/encoding_type.h), the registry, and what depends on
// it: EncodingOptions::validate, encoding_matrix, make_encoding.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <type_traits>

#include "autodiff/elementwise.h"
#include "fields/activations.h"
#include "fields/encoding_type.h"
#include "fields/encodings.h"
#include "fields/hash_grid.h"
#include "fields/integrated_positional.h"
#include "io/registry.h"

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

// |z|, with derivative sign(z) (0 at z = 0) and no higher ones.
template <typename Scalar>
class Abs final : public autodiff::ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Eigen::Ref<const autodiff::Matrix<Scalar>>& z, int max_order,
                   std::vector<autodiff::Matrix<Scalar>>& tables) const override {
    tables.resize(max_order + 1);
    for (auto& table : tables) table.resize(z.rows(), z.cols());
    tables[0] = z.cwiseAbs();
    if (max_order >= 1)
      tables[1] = z.unaryExpr([](Scalar v) { return Scalar((v > 0) - (v < 0)); });
    for (int m = 2; m <= max_order; ++m) tables[m].setZero();
  }
};

// γ(x) = [x if include_input, s ⊙ sin(x Bᵀ), s ⊙ cos(x Bᵀ)] as one sine over [B; B] with
// phases [0; π/2]; s (one per row of B) empty: all 1.
template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> sinusoids(const Eigen::MatrixXd& b, bool include_input,
                                                    const Eigen::VectorXd& scales = {}) {
  const Eigen::Index m = b.rows();
  Eigen::MatrixXd doubled(2 * m, b.cols());
  doubled << b, b;
  Eigen::VectorXd phase(2 * m);
  phase << Eigen::VectorXd::Zero(m), Eigen::VectorXd::Constant(m, std::numbers::pi / 2);
  Eigen::VectorXd doubled_scales;
  if (scales.size() > 0) {
    doubled_scales.resize(2 * m);
    doubled_scales << scales, scales;
  }
  return std::make_unique<FeatureEncoding<Scalar>>(
      doubled, phase, make_activation<Scalar>({"sine", 1.0}), include_input, doubled_scales);
}

class IdentityType final : public EncodingTypeOf<IdentityType> {
 public:
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions&, int) {
    return nullptr;
  }
};

class PositionalType final : public EncodingTypeOf<PositionalType> {
 public:
  void validate(const EncodingOptions& o) const override {
    if (o.frequencies < 1 || o.frequencies > 24)
      reject("frequencies", std::to_string(o.frequencies), "must be in [1, 24]");
  }
  Eigen::MatrixXd matrix(const EncodingOptions& o, int input_dim) const override {
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(o.frequencies * input_dim, input_dim);
    for (int l = 0; l < o.frequencies; ++l)
      for (int i = 0; i < input_dim; ++i) b(l * input_dim + i, i) = std::ldexp(std::numbers::pi, l);
    return b;
  }
  // normalize: octave l scaled by 2⁻ˡ, so that every feature's derivative is at most π
  // (AutoInt, Lindell et al. 2021: a network trained through its derivative along a ray
  // otherwise sees the high octaves amplified by 2ˡ).
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    Eigen::VectorXd scales;
    if (o.normalize) {
      scales.resize(o.frequencies * input_dim);
      for (int l = 0; l < o.frequencies; ++l) scales.segment(l * input_dim, input_dim).setConstant(std::ldexp(1.0, -l));
    }
    return sinusoids<Scalar>(PositionalType().matrix(o, input_dim), o.include_input, scales);
  }
  void read(const io::ConfigNode& e, const EncodingContext&, EncodingOptions& o) const override {
    if (e.has("frequencies")) o.frequencies = e.get_in_range("frequencies", 1, 24);
    o.include_input = e.get_or("include_input", true);
    o.normalize = e.get_or("normalize", false);
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    n["frequencies"] = o.frequencies;
    n["include_input"] = o.include_input;
    if (o.normalize) n["normalize"] = true;
  }
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    if (o.normalize) file.write_attribute(group, "encoding_normalize", std::int64_t{1});
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    o.normalize = file.has_attribute(group, "encoding_normalize") &&
                  file.read_attribute<std::int64_t>(group, "encoding_normalize") != 0;
  }
};

class FourierType final : public EncodingTypeOf<FourierType> {
 public:
  void validate(const EncodingOptions& o) const override {
    if (o.features < 1) reject("features", std::to_string(o.features), "must be >= 1");
    if (!(o.scale > 0)) reject("scale", std::to_string(o.scale), "must be > 0");
    for (std::size_t g = 0; g < o.scales.size(); ++g)
      for (double v : o.scales[g])
        if (!(v > 0)) reject("scales[" + std::to_string(g) + "]", std::to_string(v), "every σ must be > 0");
  }
  void validate_inputs(const EncodingOptions& o, int input_dim) const override {
    for (std::size_t g = 0; g < o.scales.size(); ++g) {
      const auto n = static_cast<int>(o.scales[g].size());
      if (n != 1 && n != input_dim)
        reject("scales[" + std::to_string(g) + "]", std::to_string(n) + " values",
               "needs one σ for every axis or one per axis (" + std::to_string(input_dim) + ")");
    }
  }
  // The 2π of Fourier features is folded into B. Draws row by row, so that one block at
  // `scale` is the matrix it always was.
  Eigen::MatrixXd matrix(const EncodingOptions& o, int input_dim) const override {
    std::mt19937_64 rng(o.seed);
    const std::vector<std::vector<double>> scales =
        o.scales.empty() ? std::vector<std::vector<double>>{{o.scale}} : o.scales;
    Eigen::MatrixXd b(o.features * static_cast<Eigen::Index>(scales.size()), input_dim);
    for (Eigen::Index r = 0; r < b.rows(); ++r)
      for (Eigen::Index c = 0; c < b.cols(); ++c) {
        const std::vector<double>& block = scales[static_cast<std::size_t>(r / o.features)];
        b(r, c) = 2.0 * std::numbers::pi * block[block.size() == 1 ? 0 : static_cast<std::size_t>(c)] * normal(rng);
      }
    return b;
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    return sinusoids<Scalar>(FourierType().matrix(o, input_dim), false);
  }
  void read(const io::ConfigNode& e, const EncodingContext& context,
            EncodingOptions& o) const override {
    if (e.has("features")) o.features = e.get_in_range("features", 1, 65536);
    o.scale = e.get_or("scale", o.scale);
    e.require("scale", o.scale > 0, "expected a number > 0");
    if (e.has("scales")) {
      e.require("scales", e.has_list("scales") && e.child("scales").size() > 0,
                "expected a list of scales, each a number or a list of one σ per axis");
      if (e.has("scale")) throw e.error("scales", "give scale or scales, not both");
      const io::ConfigNode list = e.child("scales");
      o.scales.clear();
      for (std::size_t g = 0; g < list.size(); ++g) {
        const io::ConfigNode item = list.at(g);
        std::vector<double> block = item.is_sequence() ? item.as<std::vector<double>>()
                                                       : std::vector<double>{item.as<double>()};
        item.require(!block.empty() && std::all_of(block.begin(), block.end(), [](double v) { return v > 0; }),
                     "expected σ > 0, a number or one per axis");
        o.scales.push_back(std::move(block));
      }
    }
    o.seed = e.has("seed") ? static_cast<std::uint64_t>(e.get_nonnegative<std::int64_t>("seed"))
                           : context.seed;
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    n["features"] = o.features;
    if (o.scales.empty()) n["scale"] = o.scale;
    for (const std::vector<double>& block : o.scales) {
      YAML::Node item;
      for (double v : block) item.push_back(v);
      item.SetStyle(YAML::EmitterStyle::Flow);
      n["scales"].push_back(item);
    }
    n["seed"] = o.seed;
  }
  // The blocks as one list of σ and the count of each.
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    if (o.scales.empty()) return;
    std::vector<double> values;
    std::vector<std::int64_t> sizes;
    for (const std::vector<double>& block : o.scales) {
      values.insert(values.end(), block.begin(), block.end());
      sizes.push_back(static_cast<std::int64_t>(block.size()));
    }
    file.write_attribute(group, "encoding_scales", std::span<const double>(values));
    file.write_attribute(group, "encoding_scales_sizes", std::span<const std::int64_t>(sizes));
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    o.scales.clear();
    if (!file.has_attribute(group, "encoding_scales")) return;
    const auto values = file.read_attribute<std::vector<double>>(group, "encoding_scales");
    const auto sizes = file.read_attribute<std::vector<std::int64_t>>(group, "encoding_scales_sizes");
    std::size_t at = 0;
    for (std::int64_t n : sizes) {
      if (n < 1 || at + static_cast<std::size_t>(n) > values.size())
        throw io::H5Error(file.path().string() + ": " + group + ": encoding_scales_sizes does not match encoding_scales");
      o.scales.emplace_back(values.begin() + static_cast<std::ptrdiff_t>(at), values.begin() + static_cast<std::ptrdiff_t>(at + n));
      at += static_cast<std::size_t>(n);
    }
  }
};

std::vector<std::string> names_or_default(std::vector<std::string> names, int input_dim) {
  if (names.empty())
    for (int a = 0; a < input_dim; ++a) names.push_back(std::string(1, "xyzw"[a % 4]));
  return names;
}

class CuspType final : public EncodingTypeOf<CuspType> {
 public:
  bool can_enter_late() const override { return true; }
  void validate(const EncodingOptions& o) const override {
    if (o.at.empty()) throw std::invalid_argument("encoding.at = []: needs at least one plane");
    for (double c : o.at)
      if (!std::isfinite(c)) reject("at", std::to_string(c), "must be finite");
    if (o.axis < 0) reject("axis", std::to_string(o.axis), "must be >= 0");
  }
  void validate_inputs(const EncodingOptions& o, int input_dim) const override {
    if (o.axis >= input_dim)
      reject("axis", std::to_string(o.axis), "must be < input_dim = " + std::to_string(input_dim));
  }
  Eigen::MatrixXd matrix(const EncodingOptions& o, int input_dim) const override {
    if (o.axis >= input_dim)
      reject("axis", std::to_string(o.axis),
             "must be < the input dimension " + std::to_string(input_dim));
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(o.at.size()), input_dim);
    b.col(o.axis).setOnes();
    return b;
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    const Eigen::MatrixXd b = CuspType().matrix(o, input_dim);
    return std::make_unique<FeatureEncoding<Scalar>>(
        b, -Eigen::Map<const Eigen::VectorXd>(o.at.data(), b.rows()),
        std::make_unique<Abs<Scalar>>(), true);
  }
  void read(const io::ConfigNode& e, const EncodingContext& context,
            EncodingOptions& o) const override {
    const std::vector<std::string> axes = names_or_default(context.input_names, context.input_dim);
    const std::string axis = e.get_choice("axis", axes);
    o.axis = static_cast<int>(std::find(axes.begin(), axes.end(), axis) - axes.begin());
    o.at = e.get<std::vector<double>>("at");
    e.require("at", !o.at.empty(), "expected a non-empty list of plane positions");
    for (double c : o.at) e.require("at", std::isfinite(c), "expected finite numbers");
    if (e.has("from_stage")) o.from_stage = e.get_in_range("from_stage", 0, 1000);
  }
  void write(const EncodingOptions& o, const EncodingContext& context,
             YAML::Node& n) const override {
    n["axis"] = names_or_default(context.input_names, context.input_dim).at(o.axis);
    n["at"] = o.at;
    if (o.from_stage > 0) n["from_stage"] = o.from_stage;
  }
  void save(io::H5Writer& file, const std::string& group,
            const EncodingOptions& o) const override {
    file.write_attribute(group, "encoding_axis", o.axis);
    file.write_attribute(group, "encoding_at", std::span<const double>(o.at));
    file.write_attribute(group, "encoding_from_stage", static_cast<std::int64_t>(o.from_stage));
  }
  void load(const io::H5Reader& file, const std::string& group,
            EncodingOptions& o) const override {
    if (file.has_attribute(group, "encoding_axis"))
      o.axis = static_cast<int>(file.read_attribute<std::int64_t>(group, "encoding_axis"));
    if (file.has_attribute(group, "encoding_at"))
      o.at = file.read_attribute<std::vector<double>>(group, "encoding_at");
    if (file.has_attribute(group, "encoding_from_stage"))
      o.from_stage = static_cast<int>(file.read_attribute<std::int64_t>(group, "encoding_from_stage"));
  }
};

using EncodingRegistry = Registry<std::unique_ptr<const EncodingType>>;

const EncodingRegistry& encodings() {
  static const EncodingRegistry registry = [] {
    EncodingRegistry r("encoding");
    r.add("identity", std::make_unique<IdentityType>());
    r.add("positional", std::make_unique<PositionalType>());
    r.add("fourier", std::make_unique<FourierType>());
    r.add("cusp", std::make_unique<CuspType>());
    r.add("hash_grid", make_hash_grid_type());
    r.add("integrated_positional", make_integrated_positional_type());
    return r;
  }();
  return registry;
}

}  // namespace

const EncodingType& encoding_type(std::string_view name) { return *encodings().at(name); }

std::vector<std::string> encoding_names() { return encodings().names(); }

bool reads_variances(const EncodingOptions& options) {
  return encoding_type(options.type).reads_variances();
}

void EncodingOptions::validate() const {
  const EncodingType& kind = encoding_type(type);
  kind.validate(*this);
  if (from_stage < 0) reject("from_stage", std::to_string(from_stage), "must be >= 0");
  if (from_stage > 0 && !kind.can_enter_late())
    reject("from_stage", std::to_string(from_stage),
           "only cusp features can enter at a later stage");
}

void EncodingOptions::validate(int input_dim) const {
  validate();
  // One bound per coordinate: variance columns have none.
  const int coordinates = encoding_type(type).reads_variances() ? input_dim / 2 : input_dim;
  if (lower.size() != upper.size() || (!lower.empty() && static_cast<int>(lower.size()) != coordinates))
    throw std::invalid_argument("encoding.lower/upper have " + std::to_string(lower.size()) + " and " +
                                std::to_string(upper.size()) +
                                " values: must both be empty or have one per input, " +
                                std::to_string(coordinates));
  for (size_t i = 0; i < lower.size(); ++i)
    if (!(std::isfinite(lower[i]) && std::isfinite(upper[i]) && lower[i] < upper[i]))
      reject("lower[" + std::to_string(i) + "]", std::to_string(lower[i]),
             "must be finite and below upper[" + std::to_string(i) + "] = " +
                 std::to_string(upper[i]));
  encoding_type(type).validate_inputs(*this, input_dim);
}

Eigen::MatrixXd encoding_matrix(const EncodingOptions& options, int input_dim) {
  options.validate();
  return encoding_type(options.type).matrix(options, input_dim);
}

template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> make_encoding(const EncodingOptions& options,
                                                        int input_dim) {
  options.validate(input_dim);
  const EncodingType& kind = encoding_type(options.type);
  if constexpr (std::is_same_v<Scalar, float>)
    return kind.make_float(options, input_dim);
  else
    return kind.make_double(options, input_dim);
}

template std::unique_ptr<autodiff::Module<float>> make_encoding<float>(const EncodingOptions&, int);
template std::unique_ptr<autodiff::Module<double>> make_encoding<double>(const EncodingOptions&, int);

}  // namespace nfield::fields
