// SPDX-License-Identifier: MIT
//
// What a condition item of the `conditions:` list says about where and what: the faces its
// `on` names and its per-channel value expressions. read_conditions
// (solvers/conditions/condition_list.h) reads items through these; pde's residuals with `on`
// and helmholtz's per-channel expressions use them too.
#pragma once

#include <string_view>
#include <vector>

#include "io/config.h"
#include "io/expression.h"
#include "solvers/core/domain.h"

namespace nfield::solvers {

// Per-channel expressions from a `value` entry (one string, or a list of output_dim), over
// the domain's variables and `constants` (problem: pde's).
std::vector<io::Expression> channel_expressions(const io::ConfigNode& node, std::string_view key,
                                                const Domain& domain, int output_dim,
                                                const io::ExpressionConstants& constants = {});

// The faces a condition item's `on` names (a face, a list of faces, or boundary); errors
// name the item's `on` and list the valid faces.
std::vector<Face> condition_faces(const io::ConfigNode& item, const Domain& domain);

// Evaluates per-channel expressions at points: n × channels.
Eigen::MatrixXd evaluate_channels(const std::vector<io::Expression>& expressions,
                                  const Eigen::MatrixXd& points);

}  // namespace nfield::solvers
