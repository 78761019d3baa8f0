// SPDX-License-Identifier: MIT
// A config written back as YAML (the run's resolved config beside its outputs).
#include <yaml-cpp/yaml.h>

#include <span>
#include <string>

#include "io/config.h"
#include "io/yaml_structure.h"

namespace nfield::io {
namespace {

// Lists of scalars on one line ([0, 1]), the way the shipped configs write them.
void flow_scalar_lists(YAML::Node node) {
  if (node.IsMap()) {
    for (auto entry : node) flow_scalar_lists(entry.second);
  } else if (node.IsSequence()) {
    bool scalars_only = true;
    for (auto element : node) {
      scalars_only = scalars_only && (element.IsScalar() || element.IsNull());
      flow_scalar_lists(element);
    }
    if (scalars_only && node.size() > 0) node.SetStyle(YAML::EmitterStyle::Flow);
  }
}

}  // namespace

std::string to_yaml(const YAML::Node& node) {
  YAML::Node copy = YAML::Clone(node);
  flow_scalar_lists(copy);
  YAML::Emitter out;
  out.SetIndent(2);
  out << copy;
  return std::string(out.c_str()) + "\n";
}

YAML::Node yaml_number(double value) { return YAML::Node(yaml_number_text(value)); }

YAML::Node yaml_numbers(std::span<const double> values) {
  YAML::Node out(YAML::NodeType::Sequence);
  for (double value : values) out.push_back(yaml_number(value));
  out.SetStyle(YAML::EmitterStyle::Flow);
  return out;
}

}  // namespace nfield::io
