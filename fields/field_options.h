// SPDX-License-Identifier: MIT
//
// The options of a field (the `field:` section of a config; fields/field_config.h reads it).
// The types registered in fields/field_types.cc:
//
//   siren  x → γ(x) → [Dense → sin(ω·)] × H → Dense              (Sitzmann et al. 2020)
//          first layer ω = first_omega, later ones hidden_omega; weights of the first layer
//          U(−1/n, 1/n), later U(−√(6/n)/ω, √(6/n)/ω), n the fan-in; biases U(−1/√n, 1/√n).
//   mlp    x → γ(x) → [Dense → σ] × H → Dense, σ = `activation`; He-uniform weights for relu,
//          Xavier-uniform otherwise, zero biases.
//   nerf   a radiance field: [x, d] → [density, r, g, b] (raw), d entering after the trunk
//          (fields/radiance_network.h); `hidden` is the trunk, `color_hidden` the colour
//          layers, `encoding` encodes x; relu by default; weights initialized as mlp.
//
//   bacon  a multiplicative filter network with band-limited outputs, one per scale
//          (fields/bacon.h; its keys: fields/bacon_type.cc).
//   acorn  adaptive blocks: a coordinate encoder gives each block of a quadtree/octree a
//          feature grid, a small decoder reads it (fields/acorn.h; keys: fields/acorn_type.cc).
//
// `latent_size` c > 0 (`field.latent: {size: c}`, siren, mlp and nerf): a latent code z ∈ R^c, one per
// instance of a family, joins the first hidden layer's output, x → γ(x) → Dense → σ → [· | z]
// → Dense → … (fields/latent_code.h). Joined there rather than to x itself: a SIREN's first
// layer draws its weights from U(−1/n, 1/n) with n its fan-in, so codes among its inputs would
// shrink the frequencies it spans on x; the first hidden layer is SIREN's own encoding of x
// (a sum of sines), so z joins the encoded coordinates, as DeepSDF joins it to its input. A
// shift of every hidden layer's activations (FiLM) is the other common choice; concatenation
// is the default and the only one so far: it adds c·width weights and nothing else. On a
// nerf field the code joins the colour layers' input instead (fields/radiance_network.h): an
// appearance code that changes a view's colours, never the geometry.
//
// `hidden` lists the H hidden widths: the SIREN reference network of the paper, d → 256,
// three 256 → 256 layers and 256 → 1, is hidden = [256, 256, 256, 256].
// Complex-valued fields use output_dim = 2 (real, imaginary).
#pragma once

#include <cstdint>
#include <any>
#include <string>
#include <vector>

#include "fields/encodings.h"

namespace nfield::fields {

struct FieldBranch;  // below: a small network of its own beside the field's (fields/field_branches.h)

struct FieldOptions {
  std::string type = "siren";         // a registered field type: siren | mlp | nerf | bacon | acorn | …
  int input_dim = 2;                  // ≥ 1 (nerf: 6)
  int output_dim = 1;                 // ≥ 1
  std::vector<int> hidden{256, 256, 256, 256};
  std::string activation;             // mlp, nerf: sine | tanh | softplus | relu | identity;
                                      // empty: the type's (FieldType::default_activation)
  double first_omega = 30.0;          // siren: ω₀ of the first layer
  double hidden_omega = 30.0;         // siren: ω of later layers (mlp sine: its frequency)
  EncodingOptions encoding;
  std::vector<int> color_hidden{64};  // nerf: widths of the colour layers
  int direction_frequencies = 4;      // nerf: octaves of the view direction's encoding
  std::uint64_t seed = 0;             // initial weights
  int latent_size = 0;                // c: a latent code per instance (above); 0: none
  // A field type's own options beyond those above, as the type's own typed struct: an outside
  // type (fields/field_type.h) sets it in FieldType::read and load, and reads it back with
  // std::any_cast in append_modules, initial_bounds, validate, write and save. Empty for the
  // built-in types.
  std::any extension;
  // Small networks of their own whose outputs follow the field's own output_dim − branches
  // outputs (an inverse problem's unknown fields, fields/field_branches.h). Empty: none.
  std::vector<FieldBranch> branches;

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

// One branch: a one-output network (type siren or mlp, options.hidden, activation, omegas;
// no encoding) of the field's input columns `inputs` (0-based, increasing), its output
// passed through softplus when `positive`. options.input_dim = inputs.size(), output_dim = 1.
struct FieldBranch {
  FieldOptions options;
  std::vector<int> inputs;
  bool positive = false;
};

// Sorted, lower-case names of the registered field types (fields/field_type.h).
std::vector<std::string> field_type_names();

// The activation a field type uses when none is given: sine (siren), tanh (mlp), relu (nerf);
// FieldType::default_activation of the registered type, the one place these defaults live.
std::string default_activation(const std::string& type);

}  // namespace nfield::fields
