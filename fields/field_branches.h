// SPDX-License-Identifier: MIT
//
// Branches: small networks of their own beside a field's network, in the same flat θ and the
// same chain of modules (an inverse problem's unknown coefficient fields, issue 26 item 2:
// `unknown_fields: {s: {hidden: [32, 32], positive: true, inputs: [x, y]}}`).
//
// The field f: R^d → R^m with branches b = 1 … B, each reading the input columns I_b, is
//
//   f(x) = [ g(x) | h_1(x[I_1]) | … | h_B(x[I_B]) ]      g: R^d → R^(m−B), h_b: R^|I_b| → R
//   h_b  = softplus(n_b)  when positive (else n_b), n_b a siren or mlp of one output.
//
// One chain of modules computes it (autodiff/on_columns.h): first a gather that appends the
// columns I_1 … I_B to x, then g's modules on columns [0, ·) carrying the gathered columns
// past them, then each branch's modules on its own columns. A gather is linear, so it acts on
// every stream alike (value, tangents, operator and Taylor streams): a branch whose inputs
// omit t has ∂h/∂t = 0 in every stream with no special case (a source s(x, y) in a space-time
// problem). So the trainer, every optimizer (the LM Jacobian is the chain's per-point
// rows), both precisions, checkpoints and `nfield eval` see one field of m outputs.
//
// θ's layout: the modules' slices in chain order — g's layers, then branch 1's, … (each
// Dense W then b, fields/dense.h). Initialization: g's layers as its type draws them, then
// each branch's as its own type would (its own dense index from 0, its own options), from
// the one engine seeded by the field's seed, in chain order: g's θ is the θ of the same field
// without branches.
//
// softplus rather than exp for `positive`: a coefficient field takes values of one order
// (a source, a diffusivity map), where softplus is nearly linear and keeps the network's
// gradients of one size; exp would square the dynamic range of the network's output.
// Pitfall: softplus(n) ≈ 0 needs n → −∞; a field that truly vanishes somewhere is better
// left free.
//
// Checkpoints (fields/field_io.h): attributes branches = B and, per branch b,
// branch_b_{type, hidden, activation, first_omega, hidden_omega, inputs, positive}; the
// dense layers of all parts are layers/K in chain order.
#pragma once

#include <string>
#include <vector>

#include "autodiff/sequential.h"
#include "fields/encodings.h"
#include "fields/field_options.h"
#include "io/hdf5_file.h"

namespace nfield::fields {

class FieldType;

// Appends the field with branches (`options.branches` non-empty, validated) to `network`
// (empty). parts[m] of each module m: 0 for g's modules and the gather, b + 1 for branch b's.
// Returns g's encoding whose features enter late, or nullptr (FieldType::append_modules).
template <typename Scalar>
FeatureEncoding<Scalar>* append_branched_network(const FieldType& type, const FieldOptions& options,
                                                 autodiff::Sequential<Scalar>& network, std::vector<int>& parts);

// The options of g: `options` less its branches and their outputs.
FieldOptions main_options(const FieldOptions& options);

// Rules of the branches (std::invalid_argument "field.branches[b].KEY = VALUE: rule"): the
// field's type is siren or mlp with one scale, each branch's type siren or mlp, inputs
// increasing in [0, input_dim), output_dim > number of branches.
void validate_branches(const FieldOptions& options);

void save_branches(io::H5Writer& file, const std::string& group, const FieldOptions& options);
// Reads them back when the group has `branches` (older checkpoints have none).
void load_branches(const io::H5Reader& file, const std::string& group, FieldOptions& options);

}  // namespace nfield::fields
