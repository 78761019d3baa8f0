// SPDX-License-Identifier: MIT
//
// Activation functions σ with derivative tables of any order, for the stream rules of
// autodiff/elementwise.h. Registered names (case-insensitive):
//
//   sine      sin(ω z), ω = `frequency` (SIREN: ω₀ = 30)   σ⁽ᵐ⁾ = ωᵐ sin(ω z + m π/2)
//   tanh      tanh z                                    σ⁽ᵐ⁾ a polynomial in tanh z
//   softplus  log(1 + eᶻ)                               σ⁽ᵐ⁾ a polynomial in sigmoid z
//   relu      max(z, 0)                                 σ' = H(z), higher orders 0
//   identity  z
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "autodiff/elementwise.h"

namespace nfield::fields {

struct ActivationSpec {
  std::string name = "sine";
  double frequency = 1.0;  // ω of sine; ignored by the others
};

template <typename Scalar>
std::unique_ptr<autodiff::ElementwiseFunction<Scalar>> make_activation(const ActivationSpec& spec);

// Sorted registered names.
std::vector<std::string> activation_names();

}  // namespace nfield::fields
