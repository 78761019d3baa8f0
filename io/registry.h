// SPDX-License-Identifier: MIT
//
// A registry of named components of one family (activations, encodings, fields, problems,
// optimizers). Names are matched case-insensitively; an unknown name raises an error that
// lists every valid name. Each family fills its registry in one plain function.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/text.h"

namespace nfield {

class UnknownNameError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

template <typename Entry>
class Registry {
 public:
  explicit Registry(std::string family) : family_(std::move(family)) {}

  void add(std::string_view name, Entry entry) {
    const std::string key = io::to_lower(name);
    if (!entries_.emplace(key, std::move(entry)).second)
      throw std::logic_error(family_ + " '" + key + "' registered twice");
  }

  bool contains(std::string_view name) const { return entries_.count(io::to_lower(name)) > 0; }

  const Entry& at(std::string_view name) const {
    auto it = entries_.find(io::to_lower(name));
    if (it == entries_.end())
      throw UnknownNameError("unknown " + family_ + " '" + std::string(name) +
                             "' (valid: " + joined_names() + ")");
    return it->second;
  }

  // Sorted, lower-case.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [name, entry] : entries_) out.push_back(name);
    return out;
  }

  std::string joined_names() const {
    std::string out;
    for (const auto& [name, entry] : entries_) out += (out.empty() ? "" : ", ") + name;
    return out;
  }

 private:
  std::string family_;
  std::map<std::string, Entry> entries_;
};

}  // namespace nfield
