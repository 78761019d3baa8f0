// SPDX-License-Identifier: MIT
#pragma once
// Strict reading of YAML configuration files on top of yaml-cpp.
//
// Every error is a ConfigError whose message starts with the place it refers to,
//   config.yaml:12:7: training.stages[1].lr: expected a number, got 'abc'
// so a user can jump straight to it. Typed getters never guess: a string where a
// number is expected, a list of the wrong length, an unknown choice, a key the program
// never reads (a typo such as `lrr:`) all stop the run with such a message.
//
// Typical use:
//
//   ConfigNode root = load_config("run.yaml", {"training.stages[0].lr=1e-3"});
//   ConfigNode training = root.child("training");
//   int seed = training.get_or("seed", 0);
//   for (std::size_t i = 0; i < training.child("stages").size(); ++i) {
//     ConfigNode stage = training.child("stages").at(i);
//     std::string optimizer = stage.get_choice("optimizer", {"adam", "lbfgs"});
//     double lr = stage.get_positive<double>("lr");
//   }
//   root.reject_unknown_keys_recursive();   // after every part has read its section
//
// Pitfalls:
//  * Unknown-key checks only know the keys that were asked for (get, get_or, has,
//    child, ...). Call reject_unknown_keys* after all reading is done.
//  * ConfigNode copies share their read-key bookkeeping; they are cheap, but not
//    thread-safe. Read configs from one thread.
//  * A key whose value is empty (`lr:` or `lr: ~`) counts as absent for get_or and is
//    an error for get.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "io/expression.h"

namespace nfield::io {

// An error in a configuration. what() is one line, `FILE:LINE:COL: KEY.PATH: message`,
// with LINE and COL 1-based; parts that are unknown are left out with their colon
// (a node created by --set has no line, the root has no key path). An unknown or a missing
// key is named by its own path (`training.lrr`), at the key or at the mapping that lacks it.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, const YAML::Mark& mark, std::string key_path,
              std::string message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }      // 1-based; 0 when unknown
  int column() const { return column_; }  // 1-based; 0 when unknown
  const std::string& key_path() const { return key_path_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_ = 0;
  int column_ = 0;
  std::string key_path_;
  std::string message_;
};

// Scalar types the getters read.
template <class T>
concept ConfigScalar = std::is_same_v<T, bool> || std::is_same_v<T, int> ||
                       std::is_same_v<T, std::int64_t> || std::is_same_v<T, double> ||
                       std::is_same_v<T, std::string>;
// Numeric types the range getters read.
template <class T>
concept ConfigNumber =
    std::is_same_v<T, int> || std::is_same_v<T, std::int64_t> || std::is_same_v<T, double>;
// Everything get<T> reads: a scalar, or a list of scalars (not bool).
template <class T>
concept ConfigValue =
    ConfigScalar<T> || std::is_same_v<T, std::vector<double>> ||
    std::is_same_v<T, std::vector<int>> || std::is_same_v<T, std::vector<std::int64_t>> ||
    std::is_same_v<T, std::vector<std::string>>;

// A node of a loaded config: a YAML node plus where it came from (file, line,
// column, dotted key path such as `training.stages[1]`).
//
// Getters that take a key require this node to be a mapping (an empty node counts as an
// empty mapping). Numbers are read strictly: `1e-3`, `.inf` and `3` are numbers, `abc`
// is not; an integer may be written `1e4` but not `1.5`; quotes do not matter ("2.5" is
// a number, 42 is also the string "42"). Booleans are true/false, yes/no or on/off in
// any case.
class ConfigNode {
 public:
  // Wraps `node`; `file` is used in messages only. Usually made by load_config.
  ConfigNode(YAML::Node node, std::string file);
  // The same, located at `mark` (a node made in code that stands for a place in the file).
  ConfigNode(YAML::Node node, YAML::Mark mark, std::string file);

  // ---- this node ---------------------------------------------------------------
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_scalar() const { return node_.IsScalar(); }
  bool is_null() const { return !node_.IsDefined() || node_.IsNull(); }
  // Entries of a mapping or a list; 0 for anything else.
  std::size_t size() const;
  // Keys of a mapping in file order (listing them does not mark them as read).
  std::vector<std::string> keys() const;
  // Element `index` of a list; an error if out of range or not a list.
  ConfigNode at(std::size_t index) const;
  // This node's own value, e.g. for elements of a list.
  template <ConfigValue T>
  T as() const;
  // This node's value as one of `choices`, like get_choice.
  std::string as_choice(const std::vector<std::string>& choices) const;

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  // Where the node starts (yaml-cpp's 0-based mark; null for nodes made in code).
  const YAML::Mark& mark() const { return mark_; }
  const YAML::Node& yaml() const { return node_; }
  // This node's place in its tree over another YAML node (a copy of it edited in code): keys
  // asked of the result count as asked of this node's tree, for reject_unknown_keys*.
  ConfigNode with_yaml(YAML::Node node) const;

  // ---- keys of a mapping ------------------------------------------------------
  // All of these mark `key` as a valid key of this mapping, present or not.
  bool has(std::string_view key) const;
  // Whether `key` is present with a list / a mapping as its value (for keys that take
  // either one value or a list or mapping of them).
  bool has_list(std::string_view key) const;
  bool has_map(std::string_view key) const;
  // Required value; `missing required key 'lr'` if absent.
  template <ConfigValue T>
  T get(std::string_view key) const;
  template <ConfigValue T>
  T get_or(std::string_view key, const T& fallback) const;
  std::string get_or(std::string_view key, const char* fallback) const;
  // A list that must have exactly `count` elements (`expected a list of 2 numbers`).
  template <ConfigScalar T>
    requires(!std::is_same_v<T, bool>)
  std::vector<T> get_list(std::string_view key, std::size_t count) const;
  // Range-checked numbers (in_range bounds are inclusive).
  template <ConfigNumber T>
  T get_positive(std::string_view key) const;
  template <ConfigNumber T>
  T get_nonnegative(std::string_view key) const;
  template <ConfigNumber T>
  T get_in_range(std::string_view key, T lowest, T highest) const;
  // One of `choices`, compared case-insensitively; returns the choice as spelled in
  // `choices`. The error lists them all: `expected one of adam, lbfgs; got 'adamw'`.
  std::string get_choice(std::string_view key, const std::vector<std::string>& choices) const;
  std::string get_choice(std::string_view key, const std::vector<std::string>& choices,
                         std::string_view fallback) const;
  // A math expression over `variables` (see io/expression.h). A syntax error is
  // reported at the file position of the offending character where it can be found.
  Expression get_expression(std::string_view key,
                            std::vector<std::string> variables = {"x", "y", "z", "t"},
                            ExpressionConstants constants = {}) const;
  Expression get_expression_or(std::string_view key, std::string_view fallback,
                               std::vector<std::string> variables = {"x", "y", "z", "t"},
                               ExpressionConstants constants = {}) const;
  // The ConfigError for an ExpressionError (io/expression.h, io/compiled_expression.h) in the
  // text at `key`, or in this node's own text: at the file column of the offending character
  // where the text sits on one line of the file, else at the text.
  ConfigError expression_error(std::string_view key, const ExpressionError& e) const;
  ConfigError expression_error(const ExpressionError& e) const;
  // A mapping or list under `key`; an error if absent or a scalar.
  ConfigNode child(std::string_view key) const;
  // Like child, but an absent (or empty) key gives an empty mapping, so that
  // `root.child_or_empty("output").get_or("every", 1000)` works without the section.
  ConfigNode child_or_empty(std::string_view key) const;

  // ---- checks -----------------------------------------------------------------
  // An error located at this node, or at the value of `key` (at this node if absent).
  ConfigError error(std::string_view message) const;
  ConfigError error(std::string_view key, std::string_view message) const;
  // Throws error(message) / error(key, message) unless `ok`. Phrase the message as
  // what was wanted: `require(lower < upper, "expected lower < upper")`.
  void require(bool ok, std::string_view message) const;
  void require(std::string_view key, bool ok, std::string_view message) const;

  // Throws at the first key of this mapping (file order) that was never asked for:
  // `unknown key 'lrr' (valid keys: lr, steps, optimizer)`. No-op for non-mappings.
  void reject_unknown_keys() const;
  // reject_unknown_keys on this node and on every mapping below it that was opened
  // through child/at/child_or_empty; sections nobody opened are the business of the
  // key that holds them.
  void reject_unknown_keys_recursive() const;
  // Checks the keys of this mapping against an explicit list (and marks those as read).
  void expect_keys(const std::vector<std::string>& allowed) const;
  // Marks every key of this mapping as read (for sections consumed as raw YAML).
  void accept_all_keys() const;

 private:
  struct KeyLog;  // per tree: key path of each opened node -> keys asked for, in order
  struct Entry {
    YAML::Node key;
    YAML::Node value;
  };
  ConfigNode(YAML::Node node, YAML::Mark mark, std::string file, std::string path,
             std::shared_ptr<KeyLog> log);
  ConfigNode make_child(const YAML::Node& node, std::string path) const;
  std::string child_path(std::string_view key) const;
  void note_key(std::string_view key) const;
  std::optional<Entry> find(std::string_view key) const;
  YAML::Node require_value(std::string_view key) const;
  void check_keys(const YAML::Node& node, const std::string& path,
                  const std::vector<std::string>& valid) const;
  void check_recursive(const YAML::Node& node, const std::string& path) const;

  YAML::Node node_;
  YAML::Mark mark_;
  std::string file_;
  std::string path_;
  std::shared_ptr<KeyLog> log_;
};

// Reads a config file. A missing or unreadable file, a YAML syntax error, a duplicate
// key or a top level that is not a mapping is a ConfigError naming the file (and
// line:column). `overrides` are `--set` assignments (see apply_override), applied in
// order after parsing.
ConfigNode load_config(const std::filesystem::path& path,
                       const std::vector<std::string>& overrides = {});
// The same for config text already in memory; `file_name` is used in messages.
ConfigNode parse_config(std::string_view text, std::string file_name,
                        const std::vector<std::string>& overrides = {});

// Applies one command-line override `key.path=value` to `root`:
//   training.seed=3             a map key (created, with missing parents, if absent)
//   training.stages[1].lr=1e-3  an element of a list (must exist)
//   training.stages.1.lr=1e-3   the same: a number after a dot indexes a list
//   domain.lower=[0, -1]        the value is parsed as YAML
// Bad syntax, an out-of-range index or stepping into a scalar is a ConfigError that
// starts with `--set 'ASSIGNMENT':`. Values set this way carry no line numbers.
void apply_override(YAML::Node& root, std::string_view assignment);

// The config as YAML text, deterministic (keys in insertion order, 2-space indent,
// lists of scalars in flow style `[1, 2]`), ending in a newline. Loading the text gives
// back the same values. Use it for the resolved config of a run: a part of the program
// that reads a section can build a YAML::Node of that section with its defaults filled
// in and put it into a resolved tree.
std::string to_yaml(const YAML::Node& node);
// A number as a YAML scalar in the shortest text that reads back to the same double
// (yaml-cpp itself writes 0.1 as 0.10000000000000001); `.inf`, `-.inf`, `.nan`.
YAML::Node yaml_number(double value);
YAML::Node yaml_numbers(std::span<const double> values);

}  // namespace nfield::io
