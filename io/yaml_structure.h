// SPDX-License-Identifier: MIT
// Checks and copies of yaml-cpp nodes that the config reader and `--set` share.
//
// yaml-cpp accepts a mapping with a repeated key or a non-scalar key and keeps one of the
// values without a word; structure_problem finds both, so that a config means one thing.
// Values given on the command line carry the marks of the `--set` text, which would be
// reported as lines of the config file; without_marks copies a node without them.
#pragma once

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>
#include <string_view>

namespace nfield::io {

// Undefined or null: a key given without a value.
bool is_empty(const YAML::Node& node);

// "an empty value", "a mapping", "a list of 3", or the scalar in quotes: for messages.
std::string describe(const YAML::Node& node);

// "a.b" from "a" and "b"; "b" from "" and "b".
std::string join_key(const std::string& path, std::string_view key);

// The first duplicate or non-scalar key under `node` (whose key path is `path`): where it is,
// the path of the mapping that holds it and what is wrong; none when every key is sound.
struct StructureProblem {
  YAML::Mark mark;
  std::string path, message;
};
std::optional<StructureProblem> structure_problem(const YAML::Node& node, const std::string& path);

YAML::Node without_marks(const YAML::Node& node);

// The shortest text that reads back as `value`, in the form YAML 1.1 readers (PyYAML) take:
// 1.0e-05 rather than 1e-05, .nan, .inf.
std::string yaml_number_text(double value);

}  // namespace nfield::io
