// SPDX-License-Identifier: MIT
//
// One registered encoding type: everything the program does that depends on the type of
// `field.encoding`. The registry (encoding_type(), fields/encoding_types.cc) maps each name,
// case-insensitively, to one of these; adding an encoding is its own files plus one
// registration line there. An unknown name is an UnknownNameError listing the valid names.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "autodiff/module.h"
#include "fields/encodings.h"
#include "io/config.h"
#include "io/hdf5_file.h"

namespace nfield::fields {

// What reading or writing `field.encoding` needs to know of the field around it.
struct EncodingContext {
  int input_dim = 2;
  std::uint64_t seed = 0;               // the field's seed: default of seeded encodings
  std::vector<std::string> input_names;  // x, y, z, t…: names of the inputs, for `axis`
};

class EncodingType {
 public:
  virtual ~EncodingType() = default;

  // The type's own rules of EncodingOptions::validate; std::invalid_argument naming the
  // option ("encoding.KEY = VALUE: rule").
  virtual void validate(const EncodingOptions&) const {}
  // Rules that need the input dimension d.
  virtual void validate_inputs(const EncodingOptions&, int /*input_dim*/) const {}

  // Whether the encoding reads a variance beside each coordinate it encodes (its input is
  // [μ₁ … μ_k, σ₁² … σ_k²], fields/integrated_positional.h): the field then takes one more
  // input per encoded coordinate (FieldType::variance_inputs), which the problem must give
  // (solvers::TakesInputVariances).
  virtual bool reads_variances() const { return false; }

  // Whether `from_stage` > 0 is allowed: features that enter at a later training stage
  // (fields/encodings.h).
  virtual bool can_enter_late() const { return false; }

  // The fixed linear part W of γ (encoding_matrix()); empty for none.
  virtual Eigen::MatrixXd matrix(const EncodingOptions&, int input_dim) const {
    return Eigen::MatrixXd(0, input_dim);
  }
  // The module, or nullptr for the identity. Options are validated.
  virtual std::unique_ptr<autodiff::Module<float>> make_float(const EncodingOptions&,
                                                              int input_dim) const = 0;
  virtual std::unique_ptr<autodiff::Module<double>> make_double(const EncodingOptions&,
                                                                int input_dim) const = 0;

  // Reads the type's keys of `field.encoding` (`type` is read already); errors are
  // io::ConfigError at the key.
  virtual void read(const io::ConfigNode&, const EncodingContext&, EncodingOptions&) const {}
  // Writes them back for the resolved config.
  virtual void write(const EncodingOptions&, const EncodingContext&, YAML::Node&) const {}

  // Checkpoint attributes of the field's group beyond those every field has
  // (fields/field_io.h).
  virtual void save(io::H5Writer&, const std::string& /*group*/, const EncodingOptions&) const {}
  virtual void load(const io::H5Reader&, const std::string& /*group*/, EncodingOptions&) const {}
};

// Implements make_float/make_double from Derived's static member template
// `template <typename Scalar> static std::unique_ptr<autodiff::Module<Scalar>> make(
//      const EncodingOptions&, int input_dim)`.
template <class Derived>
class EncodingTypeOf : public EncodingType {
 public:
  std::unique_ptr<autodiff::Module<float>> make_float(const EncodingOptions& o,
                                                      int input_dim) const final {
    return Derived::template make<float>(o, input_dim);
  }
  std::unique_ptr<autodiff::Module<double>> make_double(const EncodingOptions& o,
                                                        int input_dim) const final {
    return Derived::template make<double>(o, input_dim);
  }
};

// The registered type of `name` (case-insensitive); UnknownNameError otherwise.
const EncodingType& encoding_type(std::string_view name);

// encoding_type(options.type).reads_variances().
bool reads_variances(const EncodingOptions& options);

}  // namespace nfield::fields
