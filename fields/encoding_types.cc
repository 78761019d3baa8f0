// SPDX-License-Identifier: MIT
//
// The registry of encoding types (fields/encoding_type.h) and what depends on it:
// EncodingOptions::validate, encoding_matrix, make_encoding, entry_stage, fit_encoding. Each
// type with options lives in its own files (fields/positional_encoding.h, …); the identity,
// which has none, is here.

#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "fields/cusp_encoding.h"
#include "fields/encoding_type.h"
#include "fields/encodings.h"
#include "fields/fourier_encoding.h"
#include "fields/hash_grid.h"
#include "fields/integrated_positional.h"
#include "fields/positional_encoding.h"
#include "io/registry.h"

namespace nfield::fields {
namespace {

struct NoEncodingOptions {};

class IdentityType final : public EncodingTypeOf<IdentityType, NoEncodingOptions> {
 public:
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions&, int) {
    return nullptr;
  }
};

using EncodingRegistry = Registry<std::unique_ptr<const EncodingType>>;

const EncodingRegistry& encodings() {
  static const EncodingRegistry registry = [] {
    EncodingRegistry r("encoding");
    r.add("identity", std::make_unique<IdentityType>());
    r.add("positional", make_positional_type());
    r.add("fourier", make_fourier_type());
    r.add("cusp", make_cusp_type());
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

int entry_stage(const EncodingOptions& options) {
  return encoding_type(options.type).entry_stage(options);
}

void fit_encoding(const io::ConfigNode& node, const EncodingRun& run, EncodingOptions& options) {
  options.lower = run.lower;
  options.upper = run.upper;
  encoding_type(options.type).check_run(node, options, run);
}

void EncodingOptions::validate() const { encoding_type(type).validate(*this); }

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
      throw std::invalid_argument("encoding.lower[" + std::to_string(i) + "] = " +
                                  std::to_string(lower[i]) + ": must be finite and below upper[" +
                                  std::to_string(i) + "] = " + std::to_string(upper[i]));
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
