// SPDX-License-Identifier: MIT
// `--set KEY.PATH=VALUE`: one value of the config replaced or added before it is read.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <string>
#include <vector>

#include "io/config.h"
#include "io/yaml_structure.h"

namespace nfield::io {
namespace {

struct PathStep {
  std::string name;
  bool bracketed;  // `[2]`, as against `.2`, which indexes only where the node is a list
};

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool all_digits(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

class Override {
 public:
  explicit Override(std::string_view assignment) : where_("--set '" + std::string(assignment) + "'") {}

  ConfigError fail(const std::string& path, const std::string& message) const {
    return ConfigError(where_, YAML::Mark::null_mark(), path, message);
  }

  // name ('[' index ']')* ('.' name ('[' index ']')*)*
  std::vector<PathStep> parse_path(std::string_view key) const {
    std::vector<PathStep> steps;
    const auto at = [&](std::size_t pos) {
      return " at position " + std::to_string(pos + 1) + " of '" + std::string(key) + "'";
    };
    std::size_t pos = 0;
    while (true) {
      const std::size_t start = pos;
      while (pos < key.size() && key[pos] != '.' && key[pos] != '[' && key[pos] != ']') ++pos;
      const std::string_view name = key.substr(start, pos - start);
      if (name.empty() || trim(name).size() != name.size()) throw fail("", "expected a key name" + at(start));
      steps.push_back({std::string(name), false});
      while (pos < key.size() && key[pos] == '[') {
        const std::size_t close = key.find(']', pos);
        const std::string_view index =
            close == std::string_view::npos ? std::string_view() : key.substr(pos + 1, close - pos - 1);
        if (index.empty() || !all_digits(index)) throw fail("", "expected [INDEX]" + at(pos));
        steps.push_back({std::string(index), true});
        pos = close + 1;
      }
      if (pos == key.size()) return steps;
      if (key[pos] != '.') throw fail("", "unexpected '" + std::string(1, key[pos]) + "'" + at(pos));
      ++pos;
    }
  }

  YAML::Node parse_value(std::string_view text) const {
    YAML::Node value;
    try {
      value = without_marks(YAML::Load(std::string(text)));
    } catch (const YAML::Exception& e) {
      throw fail("", "cannot parse the value as YAML: " + e.msg);
    }
    if (const auto problem = structure_problem(value, "")) throw fail(problem->path, problem->message);
    return value;
  }

  // Walks `steps` from `root`, making mappings on the way where keys are missing, and puts
  // `value` at the end. Lists are never grown: an index past the end is an error.
  void assign(YAML::Node& root, const std::vector<PathStep>& steps, const YAML::Node& value) const {
    if (is_empty(root)) root = YAML::Node(YAML::NodeType::Map);
    YAML::Node current;
    current.reset(root);
    std::string path;
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const PathStep& step = steps[k];
      const bool last = k + 1 == steps.size();
      YAML::Node next;
      if (step.bracketed || (all_digits(step.name) && current.IsSequence())) {
        const std::size_t index = list_index(current, step.name, path);
        path += "[" + step.name + "]";
        if (last) current[index] = value;
        else next = current[index];
      } else {
        if (!current.IsMap())
          throw fail(path, "expected a mapping to set key '" + step.name + "' in, got " + describe(current));
        path = join_key(path, step.name);
        if (last) {
          current[step.name] = value;
        } else {
          next = current[step.name];
          if (is_empty(next)) {
            current[step.name] = YAML::Node(YAML::NodeType::Map);
            next.reset(current[step.name]);
          }
        }
      }
      if (!last) current.reset(next);
    }
  }

 private:
  std::size_t list_index(const YAML::Node& list, const std::string& text, const std::string& path) const {
    if (!list.IsSequence())
      throw fail(path, "expected a list to index with [" + text + "], got " + describe(list));
    std::size_t index = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), index);
    if (ec != std::errc() || index >= list.size())
      throw fail(path, "index " + text + " out of range (the list has " + std::to_string(list.size()) + " items)");
    return index;
  }

  std::string where_;
};

}  // namespace

void apply_override(YAML::Node& root, std::string_view assignment) {
  const Override override_(assignment);
  const std::size_t equals = assignment.find('=');
  if (equals == std::string_view::npos) throw override_.fail("", "expected KEY.PATH=VALUE");
  const std::string_view key = trim(assignment.substr(0, equals));
  const std::string_view value_text = trim(assignment.substr(equals + 1));
  if (key.empty()) throw override_.fail("", "missing key path before '='");
  if (value_text.empty()) throw override_.fail("", "missing value after '='");
  const std::vector<PathStep> steps = override_.parse_path(key);
  override_.assign(root, steps, override_.parse_value(value_text));
}

}  // namespace nfield::io
