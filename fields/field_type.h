// SPDX-License-Identifier: MIT
//
// One registered field type: everything the program does that depends on `field.type`. The
// registry (field_type(), fields/field_types.cc) maps each name, case-insensitively, to one
// of these; siren, mlp, nerf, bacon and acorn are registered there, and code outside the library adds its
// own with register_field_type. An unknown name is an UnknownNameError listing the valid
// names.
#pragma once

#include <yaml-cpp/yaml.h>

#include <memory>
#include <string>
#include <string_view>

#include "autodiff/sequential.h"
#include "fields/encodings.h"
#include "fields/field_options.h"
#include "io/config.h"
#include "io/hdf5_file.h"

namespace nfield::fields {

// Uniform initial weights in [−weight, weight] and biases in [−bias, bias] (0: zero).
struct InitialBounds {
  double weight = 0;
  double bias = 0;
};

class FieldType {
 public:
  virtual ~FieldType() = default;

  // The activation when `activation` is not given (also the config reader's default).
  virtual std::string default_activation() const = 0;
  // Whether `activation` is one of the type's keys (siren's layers are sines whatever it says).
  virtual bool has_activation() const { return true; }
  // The type's own rules of FieldOptions::validate; std::invalid_argument naming the option
  // ("field.KEY = VALUE: rule").
  virtual void validate(const FieldOptions&) const {}
  // Whether the type's network takes a latent code (FieldOptions::latent_size).
  virtual bool takes_latent_code() const { return false; }
  // The inputs the encoding sees (a radiance field encodes the position, not the direction),
  // its variance columns included when it reads them (EncodingType::reads_variances).
  virtual int encoded_inputs(const FieldOptions& options) const { return options.input_dim; }
  // The variance columns an encoding that reads variances adds to the problem's inputs, for
  // options whose input_dim is still the problem's: one per encoded coordinate (a coordinate
  // field [x] becomes [x, σ²]; a radiance field [x, d] becomes [x, d, σ²], 3 more).
  virtual int variance_inputs(const FieldOptions& options) const { return options.input_dim; }

  // Appends the type's modules to `network` (empty on entry); options are validated, the
  // activation resolved. Returns the encoding whose features enter at a later stage
  // (encoding.from_stage > 0), in `network`, or nullptr.
  virtual FeatureEncoding<float>* append_modules(const FieldOptions& options,
                                                 autodiff::Sequential<float>& network) const = 0;
  virtual FeatureEncoding<double>* append_modules(const FieldOptions& options,
                                                  autodiff::Sequential<double>& network) const = 0;
  // The initialization of dense layer `index` (0-based over the dense layers) of `in` inputs
  // and `out` outputs. By default He-uniform weights for relu, Xavier-uniform otherwise,
  // zero biases.
  virtual InitialBounds initial_bounds(const FieldOptions& options, int index, Eigen::Index in,
                                       Eigen::Index out) const;

  // Scales: a field with several outputs of the same quantity at different scales (bacon,
  // fields/bacon.h) has a network of output_scales() · output_dim outputs, scale 0 first;
  // fields::Field shows problems output_scale()'s, and its loss is that scale's, or the sum
  // over every scale's when trains_all_scales() (fields/field.h).
  virtual int output_scales(const FieldOptions&) const { return 1; }
  virtual int output_scale(const FieldOptions&) const { return 0; }
  virtual bool trains_all_scales(const FieldOptions&) const { return false; }
  // Per scale and input axis, the band limit in cycles per unit (scales × input_dim); empty
  // when the type has none.
  virtual Eigen::MatrixXd scale_cutoffs(const FieldOptions&) const { return {}; }
  // Why the type's fields cannot give the streams of `spec` ("gives … only; …"), empty when
  // they can: a run is refused at config load, at field.type, when a loss term needs them.
  virtual std::string refused_streams(const autodiff::StreamSpec& /*spec*/) const { return {}; }

  // Reads the type's keys of `field:` (`type`, `hidden`, `activation` and the keys every
  // field has are read elsewhere); errors are io::ConfigError at the key.
  virtual void read(const io::ConfigNode&, FieldOptions&) const {}
  // Writes them back for the resolved config.
  virtual void write(const FieldOptions&, YAML::Node&) const {}
  // Checkpoint attributes of the field's group beyond those every field has
  // (fields/field_io.h).
  virtual void save(io::H5Writer&, const std::string& /*group*/, const FieldOptions&) const {}
  virtual void load(const io::H5Reader&, const std::string& /*group*/, FieldOptions&) const {}
};

// Implements append_modules from Derived's static member template
// `template <typename Scalar> static FeatureEncoding<Scalar>* append(const FieldOptions&,
//      autodiff::Sequential<Scalar>&)`.
template <class Derived>
class FieldTypeOf : public FieldType {
 public:
  FeatureEncoding<float>* append_modules(const FieldOptions& options,
                                         autodiff::Sequential<float>& network) const final {
    return Derived::template append<float>(options, network);
  }
  FeatureEncoding<double>* append_modules(const FieldOptions& options,
                                          autodiff::Sequential<double>& network) const final {
    return Derived::template append<double>(options, network);
  }
};

// The registered type of `name` (case-insensitive); UnknownNameError otherwise.
const FieldType& field_type(std::string_view name);

// Adds a field type (`field.type: NAME`). Throws std::logic_error if the name is taken.
void register_field_type(std::string_view name, std::unique_ptr<const FieldType> type);

}  // namespace nfield::fields
