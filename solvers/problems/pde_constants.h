// SPDX-License-Identifier: MIT
//
// The two kinds of `constants:` entry of `problem: pde` that are mappings rather than numbers:
// a parameter (`nu: {range: [a, b], sampling: uniform | log}`: one more input column of the
// field, solvers/core/domain.h) and an unknown constant (`nu: {unknown: true, initial, positive |
// bounds, true, lr}`: trained with the field, solvers/core/unknowns.h). Each reader checks its
// keys and throws a located ConfigError naming the key, the value and the rule.
#pragma once

#include <string>

#include "io/config.h"
#include "solvers/core/domain.h"
#include "solvers/core/unknowns.h"

namespace nfield::solvers {

DomainParameter read_parameter(const io::ConfigNode& node, const std::string& name);
UnknownConstant read_unknown_constant(const io::ConfigNode& node, const std::string& name);

}  // namespace nfield::solvers
