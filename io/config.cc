// SPDX-License-Identifier: MIT
#include "io/config.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <system_error>
#include <utility>

#include "io/text.h"
#include "io/yaml_structure.h"

namespace nfield::io {
namespace {

std::string located_message(const std::string& file, const YAML::Mark& mark,
                            const std::string& key_path, const std::string& message) {
  std::string out = file;
  if (mark.line >= 0 && mark.column >= 0)
    out += (out.empty() ? "" : ":") + std::to_string(mark.line + 1) + ":" +
           std::to_string(mark.column + 1);
  if (!out.empty()) out += ": ";
  if (!key_path.empty()) out += key_path + ": ";
  return out + message;
}

// The entry of `choices` that `value` names, case-insensitively; "" with `message` set if none.
std::string match_choice(const std::string& value, const std::vector<std::string>& choices,
                         std::string& message) {
  for (const std::string& choice : choices)
    if (to_lower(choice) == to_lower(value)) return choice;
  message = "expected one of " + (choices.empty() ? std::string("none") : join(choices)) + "; got '" + value + "'";
  return "";
}

std::optional<double> parse_double(std::string_view text) {
  const std::string lower = to_lower(text);
  if (lower == ".inf" || lower == "+.inf") return std::numeric_limits<double>::infinity();
  if (lower == "-.inf") return -std::numeric_limits<double>::infinity();
  if (lower == ".nan") return std::numeric_limits<double>::quiet_NaN();
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty() || text.front() == '+') return std::nullopt;
  double value = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

// Integers may be written as integral floating-point text (`1e4`), not as `1.5`.
std::optional<std::int64_t> parse_integer(std::string_view text) {
  std::string_view digits = text;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  std::int64_t value = 0;
  auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (!digits.empty() && ec == std::errc() && end == digits.data() + digits.size()) return value;
  std::optional<double> real = parse_double(text);
  if (!real || !std::isfinite(*real) || std::trunc(*real) != *real ||
      std::abs(*real) >= 9.2233720368547758e18)
    return std::nullopt;
  return static_cast<std::int64_t>(*real);
}

std::optional<bool> parse_bool(std::string_view text) {
  const std::string lower = to_lower(text);
  if (lower == "true" || lower == "yes" || lower == "on") return true;
  if (lower == "false" || lower == "no" || lower == "off") return false;
  return std::nullopt;
}

// What a value of type T is called in messages: `expected a number`, `a list of numbers`.
template <class T>
struct Noun;
template <>
struct Noun<double> {
  static constexpr const char* one = "a number";
  static constexpr const char* many = "numbers";
};
template <>
struct Noun<int> {
  static constexpr const char* one = "an integer";
  static constexpr const char* many = "integers";
};
template <>
struct Noun<std::int64_t> : Noun<int> {};
template <>
struct Noun<std::string> {
  static constexpr const char* one = "a string";
  static constexpr const char* many = "strings";
};
template <>
struct Noun<bool> {
  static constexpr const char* one = "true or false";
  static constexpr const char* many = "booleans";
};

template <class T>
struct ListElement {
  using type = void;
};
template <class T>
struct ListElement<std::vector<T>> {
  using type = T;
};

// A place in a config that errors refer to.
struct Where {
  const std::string& file;
  YAML::Mark mark;
  std::string path;
  ConfigError error(const std::string& message) const {
    return ConfigError(file, mark, path, message);
  }
};

// Where `node` starts in its file; null for nodes made in code (e.g. by --set), so that
// their errors name no line rather than a wrong one.
YAML::Mark own_mark(const YAML::Node& node) {
  return node.IsDefined() ? node.Mark() : YAML::Mark::null_mark();
}

template <ConfigScalar T>
T convert_scalar(const YAML::Node& node, const Where& where) {
  const auto fail = [&] {
    return where.error(std::string("expected ") + Noun<T>::one + ", got " + describe(node));
  };
  if (!node.IsDefined() || !node.IsScalar()) throw fail();
  const std::string& text = node.Scalar();
  if constexpr (std::is_same_v<T, std::string>) {
    return text;
  } else if constexpr (std::is_same_v<T, bool>) {
    if (auto value = parse_bool(text)) return *value;
    throw fail();
  } else if constexpr (std::is_same_v<T, double>) {
    if (auto value = parse_double(text)) return *value;
    throw fail();
  } else {
    auto value = parse_integer(text);
    if (!value) throw fail();
    if (*value < std::numeric_limits<T>::min() || *value > std::numeric_limits<T>::max())
      throw where.error("expected an integer between " +
                        std::to_string(std::numeric_limits<T>::min()) + " and " +
                        std::to_string(std::numeric_limits<T>::max()) + ", got '" + text + "'");
    return static_cast<T>(*value);
  }
}

template <ConfigScalar T>
std::vector<T> convert_list(const YAML::Node& node, const Where& where,
                            std::optional<std::size_t> count) {
  const std::string wanted =
      count ? "a list of " + std::to_string(*count) + " " +
                  (*count == 1 ? std::string(Noun<T>::one).substr(std::string(Noun<T>::one).find(' ') + 1)
                               : std::string(Noun<T>::many))
            : std::string("a list of ") + Noun<T>::many;
  if (!node.IsDefined() || !node.IsSequence())
    throw where.error("expected " + wanted + ", got " + describe(node));
  if (count && node.size() != *count)
    throw where.error("expected " + wanted + ", got " + describe(node));
  std::vector<T> values;
  values.reserve(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) {
    const YAML::Node element = node[i];
    values.push_back(convert_scalar<T>(
        element,
        Where{where.file, own_mark(element), where.path + "[" + std::to_string(i) + "]"}));
  }
  return values;
}

template <ConfigValue T>
T convert(const YAML::Node& node, const Where& where) {
  if constexpr (ConfigScalar<T>)
    return convert_scalar<T>(node, where);
  else
    return convert_list<typename ListElement<T>::type>(node, where, std::nullopt);
}

template <class T>
std::string number_text(T value) {
  if constexpr (std::is_same_v<T, double>)
    return yaml_number_text(value);
  else
    return std::to_string(value);
}

}  // namespace

// ---- ConfigError ------------------------------------------------------------------

ConfigError::ConfigError(std::string file, const YAML::Mark& mark, std::string key_path,
                         std::string message)
    : std::runtime_error(located_message(file, mark, key_path, message)),
      file_(std::move(file)),
      line_(mark.line >= 0 ? mark.line + 1 : 0),
      column_(mark.line >= 0 && mark.column >= 0 ? mark.column + 1 : 0),
      key_path_(std::move(key_path)),
      message_(std::move(message)) {}

// ---- ConfigNode -------------------------------------------------------------------

struct ConfigNode::KeyLog {
  // Key path of each opened node -> keys asked for there, in the order asked.
  std::map<std::string, std::vector<std::string>, std::less<>> keys;
};

ConfigNode::ConfigNode(YAML::Node node, std::string file)
    : ConfigNode(node, node.Mark(), std::move(file), "", std::make_shared<KeyLog>()) {}

ConfigNode::ConfigNode(YAML::Node node, YAML::Mark mark, std::string file)
    : ConfigNode(std::move(node), mark, std::move(file), "", std::make_shared<KeyLog>()) {}

ConfigNode::ConfigNode(YAML::Node node, YAML::Mark mark, std::string file, std::string path,
                       std::shared_ptr<KeyLog> log)
    : node_(std::move(node)),
      mark_(mark),
      file_(std::move(file)),
      path_(std::move(path)),
      log_(std::move(log)) {
  log_->keys.try_emplace(path_);
}

ConfigNode ConfigNode::with_yaml(YAML::Node node) const { return ConfigNode(std::move(node), mark_, file_, path_, log_); }

ConfigNode ConfigNode::make_child(const YAML::Node& node, std::string path) const {
  return ConfigNode(node, own_mark(node), file_, std::move(path), log_);
}

std::string ConfigNode::child_path(std::string_view key) const { return join_key(path_, key); }

void ConfigNode::note_key(std::string_view key) const {
  std::vector<std::string>& keys = log_->keys[path_];
  if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.emplace_back(key);
}

std::optional<ConfigNode::Entry> ConfigNode::find(std::string_view key) const {
  note_key(key);
  if (!node_.IsMap()) {
    if (!is_empty(node_))
      throw error("expected a mapping with key '" + std::string(key) + "', got " +
                  describe(node_));
    return std::nullopt;
  }
  for (const auto& entry : node_)
    if (entry.first.IsScalar() && entry.first.Scalar() == key)
      return Entry{entry.first, entry.second};
  return std::nullopt;
}

YAML::Node ConfigNode::require_value(std::string_view key) const {
  std::optional<Entry> entry = find(key);
  // Located at the mapping that lacks it, named by the path the key would have.
  if (!entry)
    throw ConfigError(file_, mark_, child_path(key),
                      "missing required key '" + std::string(key) + "'");
  return entry->value;
}

std::size_t ConfigNode::size() const {
  return node_.IsMap() || node_.IsSequence() ? node_.size() : 0;
}

std::vector<std::string> ConfigNode::keys() const {
  std::vector<std::string> out;
  if (node_.IsMap())
    for (const auto& entry : node_) out.push_back(entry.first.Scalar());
  return out;
}

ConfigNode ConfigNode::at(std::size_t index) const {
  if (!node_.IsSequence()) throw error("expected a list, got " + describe(node_));
  if (index >= node_.size())
    throw error("index " + std::to_string(index) + " out of range (the list has " +
                std::to_string(node_.size()) + " items)");
  return make_child(node_[index], path_ + "[" + std::to_string(index) + "]");
}

template <ConfigValue T>
T ConfigNode::as() const {
  return convert<T>(node_, Where{file_, mark_, path_});
}

bool ConfigNode::has_list(std::string_view key) const {
  const std::optional<Entry> entry = find(key);
  return entry && entry->value.IsSequence();
}

bool ConfigNode::has_map(std::string_view key) const {
  const std::optional<Entry> entry = find(key);
  return entry && entry->value.IsMap();
}

bool ConfigNode::has(std::string_view key) const {
  note_key(key);
  if (!node_.IsMap()) return false;
  for (const auto& entry : node_)
    if (entry.first.IsScalar() && entry.first.Scalar() == key) return true;
  return false;
}

template <ConfigValue T>
T ConfigNode::get(std::string_view key) const {
  const YAML::Node value = require_value(key);
  return convert<T>(value, Where{file_, own_mark(value), child_path(key)});
}

template <ConfigValue T>
T ConfigNode::get_or(std::string_view key, const T& fallback) const {
  std::optional<Entry> entry = find(key);
  if (!entry || is_empty(entry->value)) return fallback;
  return convert<T>(entry->value, Where{file_, own_mark(entry->value), child_path(key)});
}

std::string ConfigNode::get_or(std::string_view key, const char* fallback) const {
  return get_or<std::string>(key, std::string(fallback));
}

template <ConfigScalar T>
  requires(!std::is_same_v<T, bool>)
std::vector<T> ConfigNode::get_list(std::string_view key, std::size_t count) const {
  const YAML::Node value = require_value(key);
  return convert_list<T>(value, Where{file_, own_mark(value), child_path(key)}, count);
}

template <ConfigNumber T>
T ConfigNode::get_positive(std::string_view key) const {
  const T value = get<T>(key);
  require(key, value > 0,
          std::is_same_v<T, double> ? "expected a positive number, got '" + number_text(value) + "'"
                                    : "expected a positive integer, got '" + number_text(value) + "'");
  return value;
}

template <ConfigNumber T>
T ConfigNode::get_nonnegative(std::string_view key) const {
  const T value = get<T>(key);
  require(key, value >= 0,
          std::string("expected ") + Noun<T>::one + " >= 0, got '" + number_text(value) + "'");
  return value;
}

template <ConfigNumber T>
T ConfigNode::get_in_range(std::string_view key, T lowest, T highest) const {
  const T value = get<T>(key);
  require(key, value >= lowest && value <= highest,
          std::string("expected ") + Noun<T>::one + " in [" + number_text(lowest) + ", " +
              number_text(highest) + "], got '" + number_text(value) + "'");
  return value;
}

std::string ConfigNode::get_choice(std::string_view key,
                                   const std::vector<std::string>& choices) const {
  std::string message;
  std::string choice = match_choice(get<std::string>(key), choices, message);
  if (!message.empty()) throw error(key, message);
  return choice;
}

std::string ConfigNode::as_choice(const std::vector<std::string>& choices) const {
  std::string message;
  std::string choice = match_choice(as<std::string>(), choices, message);
  if (!message.empty()) throw error(message);
  return choice;
}

std::string ConfigNode::get_choice(std::string_view key, const std::vector<std::string>& choices,
                                   std::string_view fallback) const {
  std::optional<Entry> entry = find(key);
  if (!entry || is_empty(entry->value)) return std::string(fallback);
  return get_choice(key, choices);
}

Expression ConfigNode::get_expression(std::string_view key, std::vector<std::string> variables,
                                      ExpressionConstants constants) const {
  const YAML::Node value = require_value(key);
  const std::string text =
      convert_scalar<std::string>(value, Where{file_, own_mark(value), child_path(key)});
  try {
    return Expression(text, std::move(variables), std::move(constants));
  } catch (const ExpressionError& e) {
    throw expression_error(key, e);
  }
}

namespace {

// Where an expression error points: the offending character when the text sits on one line
// of the file (plain scalars start at the mark, quoted ones, tag "!", one character later).
YAML::Mark expression_mark(const YAML::Node& value, const ExpressionError& e) {
  YAML::Mark mark = own_mark(value);
  const std::string& text = e.expression();
  if (value.IsScalar() && value.Mark().line >= 0 && e.position() != std::string::npos &&
      e.position() <= text.size() && text.find('\n') == std::string::npos &&
      value.Scalar() == text && (value.Tag() == "?" || value.Tag() == "!"))
    mark.column += static_cast<int>(e.position()) + (value.Tag() == "!" ? 1 : 0);
  return mark;
}

}  // namespace

ConfigError ConfigNode::expression_error(std::string_view key, const ExpressionError& e) const {
  std::optional<Entry> entry = find(key);
  if (!entry) return error(key, e.what());
  return ConfigError(file_, expression_mark(entry->value, e), child_path(key), e.what());
}

ConfigError ConfigNode::expression_error(const ExpressionError& e) const {
  return ConfigError(file_, expression_mark(node_, e), path_, e.what());
}

Expression ConfigNode::get_expression_or(std::string_view key, std::string_view fallback,
                                         std::vector<std::string> variables, ExpressionConstants constants) const {
  std::optional<Entry> entry = find(key);
  if (!entry || is_empty(entry->value)) return Expression(std::string(fallback), variables, constants);
  return get_expression(key, std::move(variables), std::move(constants));
}

ConfigNode ConfigNode::child(std::string_view key) const {
  const YAML::Node value = require_value(key);
  if (!value.IsMap() && !value.IsSequence())
    throw error(key, "expected a mapping or a list, got " + describe(value));
  return make_child(value, child_path(key));
}

ConfigNode ConfigNode::child_or_empty(std::string_view key) const {
  std::optional<Entry> entry = find(key);
  if (!entry || is_empty(entry->value))
    // An absent section's errors point at the mapping it would go into.
    return ConfigNode(YAML::Node(YAML::NodeType::Map), entry ? own_mark(entry->key) : mark_,
                      file_, child_path(key), log_);
  return child(key);
}

ConfigError ConfigNode::error(std::string_view message) const {
  return ConfigError(file_, mark_, path_, std::string(message));
}

ConfigError ConfigNode::error(std::string_view key, std::string_view message) const {
  YAML::Mark mark = mark_;
  if (node_.IsMap())
    for (const auto& entry : node_)
      if (entry.first.IsScalar() && entry.first.Scalar() == key) {
        mark = own_mark(entry.second);
        break;
      }
  return ConfigError(file_, mark, child_path(key), std::string(message));
}

void ConfigNode::require(bool ok, std::string_view message) const {
  if (!ok) throw error(message);
}

void ConfigNode::require(std::string_view key, bool ok, std::string_view message) const {
  if (!ok) throw error(key, message);
}

void ConfigNode::check_keys(const YAML::Node& node, const std::string& path,
                            const std::vector<std::string>& valid) const {
  if (!node.IsMap()) return;
  for (const auto& entry : node) {
    const std::string& key = entry.first.Scalar();
    if (std::find(valid.begin(), valid.end(), key) == valid.end())
      throw ConfigError(file_, own_mark(entry.first), join_key(path, key),
                        "unknown key '" + key + "' (valid keys: " + (valid.empty() ? std::string("none") : join(valid)) + ")");
  }
}

void ConfigNode::reject_unknown_keys() const { check_keys(node_, path_, log_->keys[path_]); }

void ConfigNode::check_recursive(const YAML::Node& node, const std::string& path) const {
  if (node.IsMap()) {
    auto opened = log_->keys.find(path);
    if (opened == log_->keys.end()) return;
    check_keys(node, path, opened->second);
    for (const auto& entry : node) check_recursive(entry.second, join_key(path, entry.first.Scalar()));
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i)
      check_recursive(node[i], path + "[" + std::to_string(i) + "]");
  }
}

void ConfigNode::reject_unknown_keys_recursive() const { check_recursive(node_, path_); }

void ConfigNode::expect_keys(const std::vector<std::string>& allowed) const {
  for (const std::string& key : allowed) note_key(key);
  check_keys(node_, path_, allowed);
}

void ConfigNode::accept_all_keys() const {
  for (const std::string& key : keys()) note_key(key);
}

// Explicit instantiations: the getters exist for exactly the ConfigValue types.
#define NFIELD_CONFIG_VALUE(T)                                                 \
  template T ConfigNode::as<T>() const;                                        \
  template T ConfigNode::get<T>(std::string_view) const;                       \
  template T ConfigNode::get_or<T>(std::string_view, const T&) const;
NFIELD_CONFIG_VALUE(bool)
NFIELD_CONFIG_VALUE(int)
NFIELD_CONFIG_VALUE(std::int64_t)
NFIELD_CONFIG_VALUE(double)
NFIELD_CONFIG_VALUE(std::string)
NFIELD_CONFIG_VALUE(std::vector<double>)
NFIELD_CONFIG_VALUE(std::vector<int>)
NFIELD_CONFIG_VALUE(std::vector<std::int64_t>)
NFIELD_CONFIG_VALUE(std::vector<std::string>)
#undef NFIELD_CONFIG_VALUE

#define NFIELD_CONFIG_NUMBER(T)                                                         \
  template std::vector<T> ConfigNode::get_list<T>(std::string_view, std::size_t) const; \
  template T ConfigNode::get_positive<T>(std::string_view) const;                       \
  template T ConfigNode::get_nonnegative<T>(std::string_view) const;                    \
  template T ConfigNode::get_in_range<T>(std::string_view, T, T) const;
NFIELD_CONFIG_NUMBER(int)
NFIELD_CONFIG_NUMBER(std::int64_t)
NFIELD_CONFIG_NUMBER(double)
#undef NFIELD_CONFIG_NUMBER
template std::vector<std::string> ConfigNode::get_list<std::string>(std::string_view,
                                                                    std::size_t) const;

// ---- loading and overrides ----------------------------------------------------------

ConfigNode parse_config(std::string_view text, std::string file_name,
                        const std::vector<std::string>& overrides) {
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(std::string(text));
  } catch (const YAML::Exception& e) {
    throw ConfigError(file_name, e.mark, "", "YAML syntax error: " + e.msg);
  }
  if (documents.size() > 1)
    throw ConfigError(file_name, documents[1].Mark(), "",
                      "expected one YAML document, found " + std::to_string(documents.size()));
  YAML::Node root = documents.empty() ? YAML::Node(YAML::NodeType::Map) : documents[0];
  if (const auto problem = structure_problem(root, ""))
    throw ConfigError(file_name, problem->mark, problem->path, problem->message);
  for (const std::string& assignment : overrides) apply_override(root, assignment);
  if (is_empty(root)) root.reset(YAML::Node(YAML::NodeType::Map));
  if (!root.IsMap())
    throw ConfigError(file_name, root.Mark(), "",
                      "expected a mapping of keys at the top level, got " + describe(root));
  // A file without keys (empty, comments only) is still a place: errors about the keys it
  // lacks point at its start.
  const YAML::Mark mark = root.Mark().is_null() ? YAML::Mark() : root.Mark();
  return ConfigNode(root, mark, std::move(file_name));
}

ConfigNode load_config(const std::filesystem::path& path,
                       const std::vector<std::string>& overrides) {
  const std::string file = path.string();
  const YAML::Mark nowhere = YAML::Mark::null_mark();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw ConfigError(file, nowhere, "", "config file not found");
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError(file, nowhere, "", "is a directory, not a config file");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in || in.bad()) throw ConfigError(file, nowhere, "", "cannot read config file");
  return parse_config(text.str(), file, overrides);
}

}  // namespace nfield::io
