// SPDX-License-Identifier: MIT
//
// Fields in HDF5, in a layout h5py users read directly:
//
//   /field                      group; attributes: type, input_dim, output_dim, hidden,
//                               activation, first_omega, hidden_omega, seed, precision,
//                               encoding_type, encoding_lower, encoding_upper (when set),
//                               and each encoding type's own (EncodingType::save:
//                               encoding_frequencies, encoding_features, encoding_axis, …,
//                               encoding_levels, …; files from before 2026-11 carry
//                               encoding_frequencies, _include_input, _features, _scale and
//                               _seed for every type, and each type reads only its own);
//                               with branches (fields/field_branches.h) also branches and
//                               branch_K_{type, hidden, activation, first_omega,
//                               hidden_omega, inputs, positive}
//   /field/layers/K/weight      out × in (as PyTorch's nn.Linear.weight), layer K = 0, 1, …
//                               (dense layers only: the field's own, then each branch's)
//   /field/layers/K/bias        out
//   /field/encoding             the fixed encoding matrix B (m × d), when there is one
//   /field/latent_code          the field's own latent code z (c values; attribute latent_size),
//                               when it takes one (fields/latent_code.h; a family's table of
//                               codes is /latent/codes, solvers/run/latent_run.h)
//   /field/encoding_parameters  the trained parameters of an encoding, when it has any, in
//                               its own layout (hash_grid: the tables level after level,
//                               rows × features, fields/hash_grid.h)
//
// Values are stored in the field's own precision, so a save/load round trip is bit-exact.
#pragma once

#include <string>

#include "fields/field.h"
#include "io/hdf5_file.h"

namespace nfield::fields {

template <typename Scalar>
void save_field(io::H5Writer& file, const Field<Scalar>& field, const std::string& group = "field");

// Reads a field saved by save_field, converting to Scalar if it was saved in the other
// precision. Throws io::H5Error naming the file and what is missing.
template <typename Scalar>
Field<Scalar> load_field(const io::H5Reader& file, const std::string& group = "field");

// The options stored with a saved field.
FieldOptions load_field_options(const io::H5Reader& file, const std::string& group = "field");

}  // namespace nfield::fields
