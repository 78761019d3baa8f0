// SPDX-License-Identifier: MIT
#include "fields/positional_encoding.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fields/encoding_type.h"

namespace nfield::fields {

void PositionalOptions::validate() const {
  if (frequencies < 1 || frequencies > 24)
    throw std::invalid_argument("encoding.frequencies = " + std::to_string(frequencies) +
                                ": must be in [1, 24]");
}

namespace {

class PositionalType final : public EncodingTypeOf<PositionalType, PositionalOptions> {
 public:
  void validate(const EncodingOptions& o) const override { own(o).validate(); }
  Eigen::MatrixXd matrix(const EncodingOptions& o, int input_dim) const override {
    const int frequencies = own(o).frequencies;
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(frequencies * input_dim, input_dim);
    for (int l = 0; l < frequencies; ++l)
      for (int i = 0; i < input_dim; ++i) b(l * input_dim + i, i) = std::ldexp(std::numbers::pi, l);
    return b;
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    const PositionalOptions& p = own(o);
    Eigen::VectorXd scales;
    if (p.normalize) {
      scales.resize(p.frequencies * input_dim);
      for (int l = 0; l < p.frequencies; ++l)
        scales.segment(l * input_dim, input_dim).setConstant(std::ldexp(1.0, -l));
    }
    return make_sinusoids<Scalar>(PositionalType().matrix(o, input_dim), p.include_input, scales);
  }
  void read(const io::ConfigNode& e, const EncodingContext&, EncodingOptions& o) const override {
    PositionalOptions p;
    if (e.has("frequencies")) p.frequencies = e.get_in_range("frequencies", 1, 24);
    p.include_input = e.get_or("include_input", true);
    p.normalize = e.get_or("normalize", false);
    o.own = p;
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    const PositionalOptions& p = own(o);
    n["frequencies"] = p.frequencies;
    n["include_input"] = p.include_input;
    if (p.normalize) n["normalize"] = true;
  }
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    const PositionalOptions& p = own(o);
    file.write_attribute(group, "encoding_frequencies", p.frequencies);
    file.write_attribute(group, "encoding_include_input", static_cast<std::int64_t>(p.include_input));
    if (p.normalize) file.write_attribute(group, "encoding_normalize", std::int64_t{1});
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    PositionalOptions p;
    auto integer = [&](const char* name, std::int64_t fallback) {
      return file.has_attribute(group, name) ? file.read_attribute<std::int64_t>(group, name) : fallback;
    };
    p.frequencies = static_cast<int>(integer("encoding_frequencies", p.frequencies));
    p.include_input = integer("encoding_include_input", p.include_input) != 0;
    p.normalize = integer("encoding_normalize", 0) != 0;
    o.own = p;
  }
};

}  // namespace

std::unique_ptr<const EncodingType> make_positional_type() {
  return std::make_unique<PositionalType>();
}

}  // namespace nfield::fields
