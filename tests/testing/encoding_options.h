// SPDX-License-Identifier: MIT
//
// Every encoding's keys in one struct, for tests that sweep one set of values over encoding
// types (tests/testing/stream_checks.h) or read a field's encoding back from the definition
// (tests/testing/reference_field.h). The library has no such struct: each encoding owns its
// own (fields/positional_encoding.h, …), and encoding_of() fills the one of the type asked.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fields/cusp_encoding.h"
#include "fields/fourier_encoding.h"
#include "fields/hash_grid.h"
#include "fields/integrated_positional.h"
#include "fields/positional_encoding.h"
#include "io/text.h"

namespace nfield::testutil {

struct AnyEncoding {
  int frequencies = 6;  // positional, integrated_positional
  bool include_input = true;  // positional, integrated_positional, hash_grid
  bool normalize = false;     // positional
  int features = 128;         // fourier
  double scale = 10.0;
  std::vector<std::vector<double>> scales;
  std::uint64_t seed = 0;
  int axis = 0;  // cusp
  std::vector<double> at;
  int from_stage = 0;
  int levels = 16;  // hash_grid
  int features_per_level = 2;
  int log2_table_size = 19;
  int base_resolution = 16;
  int finest_resolution = 512;
  std::string interpolation = "linear";
  double init_scale = 1e-4;

  bool operator==(const AnyEncoding&) const = default;
};

// Options of `type` with the values of `a` that its own struct has (identity: none).
inline fields::EncodingOptions encoding_of(const std::string& type, const AnyEncoding& a = {}) {
  fields::EncodingOptions o;
  o.type = type;
  const std::string kind = io::to_lower(type);
  if (kind == "positional")
    o.own = fields::PositionalOptions{a.frequencies, a.include_input, a.normalize};
  else if (kind == "integrated_positional")
    o.own = fields::IntegratedPositionalOptions{a.frequencies, a.include_input};
  else if (kind == "fourier")
    o.own = fields::FourierOptions{a.features, a.scale, a.scales, a.seed};
  else if (kind == "cusp")
    o.own = fields::CuspOptions{a.axis, a.at, a.from_stage};
  else if (kind == "hash_grid")
    o.own = fields::HashGridOptions{a.levels, a.features_per_level, a.log2_table_size, a.base_resolution,
                                    a.finest_resolution, a.interpolation, a.include_input, a.init_scale};
  return o;
}

// The values of the struct `o` holds, the others at AnyEncoding's defaults.
inline AnyEncoding any_encoding(const fields::EncodingOptions& o) {
  AnyEncoding a;
  const std::string kind = io::to_lower(o.type);
  if (kind == "positional") {
    const auto& p = fields::own_options<fields::PositionalOptions>(o);
    a.frequencies = p.frequencies, a.include_input = p.include_input, a.normalize = p.normalize;
  } else if (kind == "integrated_positional") {
    const auto& p = fields::own_options<fields::IntegratedPositionalOptions>(o);
    a.frequencies = p.frequencies, a.include_input = p.include_input;
  } else if (kind == "fourier") {
    const auto& f = fields::own_options<fields::FourierOptions>(o);
    a.features = f.features, a.scale = f.scale, a.scales = f.scales, a.seed = f.seed;
  } else if (kind == "cusp") {
    const auto& c = fields::own_options<fields::CuspOptions>(o);
    a.axis = c.axis, a.at = c.at, a.from_stage = c.from_stage;
  } else if (kind == "hash_grid") {
    const auto& h = fields::own_options<fields::HashGridOptions>(o);
    a.levels = h.levels, a.features_per_level = h.features_per_level, a.log2_table_size = h.log2_table_size;
    a.base_resolution = h.base_resolution, a.finest_resolution = h.finest_resolution;
    a.interpolation = h.interpolation, a.include_input = h.include_input, a.init_scale = h.init_scale;
  }
  return a;
}

}  // namespace nfield::testutil
