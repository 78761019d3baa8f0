// SPDX-License-Identifier: MIT
//
// The `conditions:` list of a config, read once into typed items that every consumer reads:
// the soft loss terms (solvers/conditions/conditions.h), the hard ansatz
// (solvers/conditions/hard_constraints.h), the wave equation's finite-difference reference
// (solvers/problems/wave.cc) and problem: pde's boundary residuals. The type, faces and
// values of an item are parsed here and nowhere else.
//
//   - {on: boundary, type: dirichlet, value: "0"}                 u = g
//   - {on: [x_min], type: neumann, value: {u: "0", v: "x"}}       ∂u/∂n = g, ∂v/∂n = x
//   - {on: [x_max], type: robin, a: 1, b: "0.5", value: {u: "1"}} a u + b ∂u/∂n = g
//   - {on: [x_min, x_max], type: periodic, outputs: [u]}         u, ∂u/∂x equal on both
//   - {on: initial, type: value, value: "sin(pi*x)"}              u(x, t0) = g
//   - {on: initial, type: velocity, value: {u: "0"}}              u_t(x, t0) = g
//   - {on: [y_max], type: residual, residual: "u_y + u*v - 1"}    (problem: pde) = 0
//
// `value` has three forms: one expression (the first output; every other output gets 0: the
// built-in problems' form), a list of one expression per output (complex fields: real,
// imaginary), or a mapping from output names to expressions, where an output not named is
// free (this item says nothing about it). Robin's `a` and `b` are one expression each,
// shared by the outputs `value` constrains; ∂/∂n is along each face's outward normal.
// Periodic pairs opposite faces of one axis: at each pair of points that differ only in that
// axis, the values and the derivatives along it agree (one loss term over groups of two
// points, so Adam and L-BFGS train it; an lm stage is refused at load); `outputs` (default
// all) names the outputs it ties.
//
// `weight` (default 1, ≥ 0) scales the item's loss term; `enforce: hard` (dirichlet and
// initial value/velocity only, every output given a value) makes it exact through the ansatz
// instead, and then it takes no weight; `time_scale` belongs to a hard initial value.
//
// On a domain with a geometry (domain.geometry) `on` names parts instead of faces: a
// primitive's name, a list of them, or `boundary`, optionally narrowed by `where: "x < -0.49"`
// (an expression over x, y(, z), nonzero on the points kept); the points are drawn on those
// parts (Domain::sample_boundary) and ∂/∂n is along each point's own outward normal
// (Domain::boundary_normals). Periodic items need a box; a hard item takes parts by name
// only (its φ is the distance to the named parts, not to a `where` subset).
//
// Refused with a located error: an unknown type, face, part or output; a periodic `on` that is not
// two opposite faces; hard enforcement where the problem or the type has none; `initial`
// without a time interval; unknown keys.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/config.h"
#include "io/expression.h"
#include "solvers/core/domain.h"
#include "solvers/geometry/geometry.h"

namespace nfield::solvers {

enum class ConditionType { kDirichlet, kNeumann, kRobin, kPeriodic, kResidual, kInitialValue, kInitialVelocity };

struct ConditionItem {
  explicit ConditionItem(io::ConfigNode item) : node(std::move(item)) {}

  ConditionType type = ConditionType::kDirichlet;
  bool initial = false;     // at t0 (initial value, velocity, or a residual on: initial)
  std::vector<Face> faces;  // on faces; periodic: the lower face, then the upper one
  // On a domain with a geometry: the parts (and `where`) instead of faces.
  std::optional<geometry::Selection> parts;
  // The outputs the item constrains (channels, increasing), and per channel its value g
  // (set for those channels; not for periodic and residual items).
  std::vector<int> outputs;
  std::vector<std::optional<io::Expression>> values;
  std::optional<io::Expression> robin_a, robin_b;  // robin: a u + b ∂u/∂n = g
  std::string residual;                            // residual: the expression's text
  double weight = 1;
  bool hard = false;
  double time_scale = 0;  // hard initial value: s > 0 for ψ = tanh(τ/s)
  double fade = 0;        // hard Dirichlet on parts, `fade: δ` > 0: A = g·exp(−φ/δ)
  double saturate = 0;    // hard Dirichlet on parts, `saturate: s` > 0: D = s·tanh(φ/s)
  std::size_t index = 0;  // its position in the list (term names)
  io::ConfigNode node;    // the item, for errors found later

  // The value expressions of every channel, 0 where the item has none.
  std::vector<io::Expression> channel_values(const Domain& domain) const;
};

struct ConditionReading {
  std::vector<std::string> outputs{"u"};  // the problem's output names (map form, errors)
  io::ExpressionConstants constants;      // what value expressions may read besides x, y, z, t
  bool allow_hard = false;                // the problem applies an ansatz (poisson, wave, pde)
  bool allow_residual = false;            // type: residual (problem: pde)
};

// Reads a `conditions:` list (null: none); ConfigError at the offending key.
std::vector<ConditionItem> read_conditions(const io::ConfigNode& conditions, const Domain& domain,
                                           const ConditionReading& reading);

}  // namespace nfield::solvers
