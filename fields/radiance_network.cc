// SPDX-License-Identifier: MIT
#include "fields/radiance_network.h"

#include "autodiff/on_columns.h"
#include "autodiff/permute_columns.h"
#include "fields/activation_layer.h"
#include "fields/dense.h"
#include "fields/encoding_type.h"
#include "fields/encodings.h"
#include "fields/latent_code.h"
#include "fields/positional_encoding.h"

namespace nfield::fields {
namespace {

// Appends `module` reading columns [begin, begin + its input width) of the current output,
// the others carried.
template <typename Scalar>
void add_on(autodiff::Sequential<Scalar>& network, std::unique_ptr<autodiff::Module<Scalar>> module,
            Eigen::Index begin, Eigen::Index width) {
  network.add(std::make_unique<autodiff::OnColumns<Scalar>>(std::move(module), begin, width));
}

}  // namespace

template <typename Scalar>
void add_radiance_modules(const FieldOptions& options, autodiff::Sequential<Scalar>& network) {
  constexpr Eigen::Index kCarried = 3;  // d, through the trunk
  const ActivationSpec activation{options.activation, options.hidden_omega};
  Eigen::Index width = 3;  // the columns the next trunk module reads; d follows them
  if (reads_variances(options.encoding)) {
    // [x, d, σ²] → [x, σ², d]: the encoding reads the means and variances together.
    network.add(std::make_unique<autodiff::PermuteColumns<Scalar>>(std::vector<Eigen::Index>{0, 1, 2, 6, 7, 8, 3, 4, 5}));
    width = 6;
  }
  if (auto encoding = make_encoding<Scalar>(options.encoding, static_cast<int>(width))) {
    const Eigen::Index encoded = encoding->output_width();
    add_on<Scalar>(network, std::move(encoding), 0, width + kCarried);
    width = encoded;
  }
  for (int h : options.hidden) {
    add_on<Scalar>(network, std::make_unique<Dense<Scalar>>(width, h), 0, width + kCarried);
    add_on<Scalar>(network, std::make_unique<ActivationLayer<Scalar>>(activation, h), 0, h + kCarried);
    width = h;
  }
  const Eigen::Index features = width;
  add_on<Scalar>(network, std::make_unique<Dense<Scalar>>(width, 1 + features), 0, width + kCarried);
  // [s, f, d] → [s, f, γ_d(d)]
  const EncodingOptions direction = encoding_options(
      PositionalOptions{.frequencies = options.direction_frequencies, .include_input = true});
  auto direction_encoding = make_encoding<Scalar>(direction, 3);
  const Eigen::Index encoded_direction = direction_encoding->output_width();
  add_on<Scalar>(network, std::move(direction_encoding), 1 + features, 1 + features + kCarried);
  // The colour layers read [f, γ_d(d)] (and an appearance code z) and carry s in column 0.
  width = features + encoded_direction;
  if (options.latent_size > 0) {
    add_on<Scalar>(network, std::make_unique<LatentCode<Scalar>>(width, options.latent_size), 1, 1 + width);
    width += options.latent_size;
  }
  for (int c : options.color_hidden) {
    add_on<Scalar>(network, std::make_unique<Dense<Scalar>>(width, c), 1, 1 + width);
    add_on<Scalar>(network, std::make_unique<ActivationLayer<Scalar>>(activation, c), 1, 1 + c);
    width = c;
  }
  add_on<Scalar>(network, std::make_unique<Dense<Scalar>>(width, 3), 1, 1 + width);
}

template void add_radiance_modules<float>(const FieldOptions&, autodiff::Sequential<float>&);
template void add_radiance_modules<double>(const FieldOptions&, autodiff::Sequential<double>&);

}  // namespace nfield::fields
