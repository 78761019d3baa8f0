// SPDX-License-Identifier: MIT
#include "io/yaml_structure.h"

#include <array>
#include <charconv>
#include <cmath>
#include <map>


namespace nfield::io {

bool is_empty(const YAML::Node& node) { return !node.IsDefined() || node.IsNull(); }

std::string describe(const YAML::Node& node) {
  if (is_empty(node)) return "an empty value";
  if (node.IsMap()) return "a mapping";
  if (node.IsSequence()) return "a list of " + std::to_string(node.size());
  return "'" + node.Scalar() + "'";
}

std::string join_key(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::optional<StructureProblem> structure_problem(const YAML::Node& node, const std::string& path) {
  if (node.IsMap()) {
    std::map<std::string, int, std::less<>> first_line;
    for (const auto& entry : node) {
      const YAML::Node& key = entry.first;
      if (!key.IsScalar()) return StructureProblem{key.Mark(), path, "expected a plain name as key, got " + describe(key)};
      auto [it, inserted] = first_line.emplace(key.Scalar(), key.Mark().line + 1);
      if (!inserted)
        return StructureProblem{key.Mark(), path,
                                "duplicate key '" + key.Scalar() + "' (first on line " + std::to_string(it->second) + ")"};
      if (auto problem = structure_problem(entry.second, join_key(path, key.Scalar()))) return problem;
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i)
      if (auto problem = structure_problem(node[i], path + "[" + std::to_string(i) + "]")) return problem;
  }
  return std::nullopt;
}

YAML::Node without_marks(const YAML::Node& node) {
  if (is_empty(node)) return YAML::Node(YAML::NodeType::Null);
  if (node.IsScalar()) {
    YAML::Node out(node.Scalar());
    out.SetTag(node.Tag());
    return out;
  }
  YAML::Node out(node.IsMap() ? YAML::NodeType::Map : YAML::NodeType::Sequence);
  if (node.IsMap()) {
    for (const auto& entry : node) out[without_marks(entry.first)] = without_marks(entry.second);
  } else {
    for (const auto& element : node) out.push_back(without_marks(element));
  }
  out.SetStyle(node.Style());
  return out;
}

std::string yaml_number_text(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  std::array<char, 64> buffer;
  auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  std::string text(buffer.data(), end);
  // YAML 1.1 readers (PyYAML) want a dot in exponent notation: 1e-05 -> 1.0e-05.
  if (auto e = text.find('e'); e != std::string::npos && text.find('.') == std::string::npos)
    text.insert(e, ".0");
  return text;
}

}  // namespace nfield::io
