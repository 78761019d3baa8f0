// SPDX-License-Identifier: MIT
#include "solvers/run/field_setup.h"

#include <string>

#include "fields/encoding_type.h"
#include "solvers/core/problem_capabilities.h"

namespace nfield::solvers {
namespace {

// The problem appends the variances the encoding reads, one per coordinate it encodes.
void give_input_variances(RunSetup& s, const io::ConfigNode& encoding) {
  auto* variances = capability<TakesInputVariances>(*s.problem);
  if (!variances)
    throw encoding.error("type", "'" + s.field.encoding.type +
                                     "' reads a variance beside each coordinate, and problem '" +
                                     s.root.get<std::string>("problem") +
                                     "' gives none (problem: nerf does: each sample's frustum)");
  const int coordinates = s.problem->field_input_dim();
  variances->give_input_variances();
  const int given = s.problem->field_input_dim() - coordinates;
  if (s.field.input_dim - coordinates != given)
    throw encoding.error("type", "'" + s.field.encoding.type + "' on a '" + s.field.type + "' field reads " +
                                     std::to_string(s.field.input_dim - coordinates) + " variances, problem '" +
                                     s.root.get<std::string>("problem") + "' gives " + std::to_string(given) +
                                     " (one per position coordinate: use field.type: nerf)");
}

}  // namespace

void fit_field_to_run(RunSetup& s) {
  const io::ConfigNode encoding = s.root.child_or_empty("field").child_or_empty("encoding");
  if (fields::reads_variances(s.field.encoding)) give_input_variances(s, encoding);
  const Eigen::VectorXd lower = s.problem->domain().input_lower();
  const Eigen::VectorXd upper = s.problem->domain().input_upper();
  fields::EncodingRun run;
  run.lower.assign(lower.data(), lower.data() + lower.size());
  run.upper.assign(upper.data(), upper.data() + upper.size());
  run.stages = static_cast<int>(s.training.stages.size());
  fields::fit_encoding(encoding, run, s.field.encoding);
}

}  // namespace nfield::solvers
