// SPDX-License-Identifier: MIT
//
// `field.encoding: {type: cusp, axis: y, at: [0.5], from_stage: 0}`:
//   γ(x) = [x, |x_a − c₁|, …, |x_a − c_k|]   for the planes x_a = c_k (a = axis, c = at).
//
// Cusp features (Tseng, Lin, Hu and Lai 2023, cusp-capturing PINNs) let a smooth network
// represent a function that is continuous across a plane but whose normal derivative jumps
// there, as travel times in a layered medium or potentials across a material interface do.
// With f₋, f₊ smooth on either side and equal on the plane, f₊ − f₋ = (x_a − c) h, so
//   f = (f₊ + f₋)/2 + |x_a − c| h/2,
// a smooth function of [x, |x_a − c|]. A network of x alone has to round the kink off over
// a width that only shrinks with the network's size.
// Pitfall: |·| has derivative sign(z) (0 on the plane) and no higher ones in the streams; the
// δ of the second derivative on the plane is not there. Residuals of first order (eikonal)
// are exact on both sides; a second-order residual must not be asked across the plane.
//
// Cusp features that enter late (`from_stage: k`): the first layer's weights on the cusp
// features start at zero, and in the training stages before k the features are switched off
// (zero in every stream), so those weights get zero gradients and zero Jacobian columns from
// every optimizer and stay at zero; at stage k the features are switched on, with the field
// unchanged at that moment. A network that can form a kink on the plane from the start can
// also form the wrong one: on the two-layer Eikonal example (configs/accuracy_eikonal_layered
// .yaml) Adam with cusp features put a steep layer on the fast side of the interface in place
// of the head wave below it, which features entering for the Levenberg–Marquardt stages
// avoid (figures: docs/experiments.md).
//
// The field learns the stage through entry_stage() (fields/encodings.h); the run driver lets
// the type refuse a stage the run does not have (EncodingType::check_run).
//
// Checkpoint attributes: encoding_axis, encoding_at, encoding_from_stage.
#pragma once

#include <memory>
#include <string_view>
#include <vector>

#include "fields/encodings.h"

namespace nfield::fields {

class EncodingType;

struct CuspOptions {
  static constexpr std::string_view kType = "cusp";
  int axis = 0;            // the input a normal to the planes (config: its name, x, y, …)
  std::vector<double> at;  // the planes x_a = c, at least one
  int from_stage = 0;      // the training stage at which the features enter

  // std::invalid_argument naming the key, its value and the rule.
  void validate() const;
  // validate(), then axis < d.
  void validate(int input_dim) const;
};

// The registry entry of `cusp` (fields/encoding_type.h).
std::unique_ptr<const EncodingType> make_cusp_type();

}  // namespace nfield::fields
