// SPDX-License-Identifier: MIT
//
// One registered encoding type: everything the program does that depends on the type of
// `field.encoding`. The registry (encoding_type(), fields/encoding_types.cc) maps each name,
// case-insensitively, to one of these; adding an encoding is its own files plus one
// registration line there. An unknown name is an UnknownNameError listing the valid names.
//
// A type owns its options: its own struct (PositionalOptions, …) beside it, which its entry
// reads from the config (EncodingOptions::own), validates, writes back, saves as checkpoint
// attributes and loads. EncodingTypeOf<Derived, Own> gives the entry own(options), the
// struct. Nothing outside the entry knows its keys: what the run around the field must know
// goes through the hooks below (entry_stage, check_run, reads_variances).
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

// What the run around the field knows once the problem and `training:` are read: the
// problem's domain box (one bound per coordinate) and the number of training stages.
struct EncodingRun {
  std::vector<double> lower, upper;
  int stages = 1;
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

  // The training stage at which the features enter (0: from the start; cusp's from_stage,
  // fields/cusp_encoding.h).
  virtual int entry_stage(const EncodingOptions&) const { return 0; }
  // Checks the options against the run (a stage index the run has); errors are
  // io::ConfigError at the key of `node`, the config's `field.encoding`.
  virtual void check_run(const io::ConfigNode& /*node*/, const EncodingOptions&,
                         const EncodingRun&) const {}

  // The fixed linear part W of γ (encoding_matrix()); empty for none.
  virtual Eigen::MatrixXd matrix(const EncodingOptions&, int input_dim) const {
    return Eigen::MatrixXd(0, input_dim);
  }
  // The module, or nullptr for the identity. Options are validated.
  virtual std::unique_ptr<autodiff::Module<float>> make_float(const EncodingOptions&,
                                                              int input_dim) const = 0;
  virtual std::unique_ptr<autodiff::Module<double>> make_double(const EncodingOptions&,
                                                                int input_dim) const = 0;

  // Reads the type's keys of `field.encoding` (`type` is read already) into its own struct,
  // EncodingOptions::own; errors are io::ConfigError at the key.
  virtual void read(const io::ConfigNode&, const EncodingContext&, EncodingOptions&) const {}
  // Writes them back for the resolved config.
  virtual void write(const EncodingOptions&, const EncodingContext&, YAML::Node&) const {}

  // Checkpoint attributes of the field's group beyond those every field has
  // (fields/field_io.h), named encoding_KEY. load sets EncodingOptions::own; an attribute
  // that is absent keeps its default (files from before a key existed).
  virtual void save(io::H5Writer&, const std::string& /*group*/, const EncodingOptions&) const {}
  virtual void load(const io::H5Reader&, const std::string& /*group*/, EncodingOptions&) const {}
};

// Implements make_float/make_double from Derived's static member template
// `template <typename Scalar> static std::unique_ptr<autodiff::Module<Scalar>> make(
//      const EncodingOptions&, int input_dim)`, and gives Derived its own options struct.
template <class Derived, class Own>
class EncodingTypeOf : public EncodingType {
 public:
  // The type's options (own_options<Own>, fields/encodings.h).
  static const Own& own(const EncodingOptions& o) { return own_options<Own>(o); }

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

// What the run driver tells a field's encoding: stores the domain box (every field keeps it,
// EncodingOptions::lower/upper) and lets the type check its options against the run
// (EncodingType::check_run; errors at the keys of `node`, the config's `field.encoding`).
void fit_encoding(const io::ConfigNode& node, const EncodingRun& run, EncodingOptions& options);

}  // namespace nfield::fields
