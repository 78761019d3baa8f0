// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_constants.h"

#include <cmath>
#include <utility>
#include <vector>

#include "io/text.h"

namespace nfield::solvers {

// `name: {range: [lower, upper], sampling: uniform | log}`: a parameter column of the field
// (solvers/core/domain.h, DomainParameter); expressions read it as they read x or t.
DomainParameter read_parameter(const io::ConfigNode& node, const std::string& name) {
  if (node.has("unknown"))
    throw node.error("unknown", "'" + name + "' is declared as a range (a field input) and as unknown; "
                                "give one: range: [lower, upper] or unknown: true");
  DomainParameter p;
  p.name = name;
  const std::vector<double> range = node.get_list<double>("range", 2);
  p.lower = range[0];
  p.upper = range[1];
  node.require("range", std::isfinite(p.lower) && std::isfinite(p.upper) && p.lower < p.upper,
               "expected [lower, upper] with lower < upper, got [" + io::format_number(p.lower) + ", " +
                   io::format_number(p.upper) + "]");
  if (node.has("sampling")) p.log = node.get_choice("sampling", {"uniform", "log"}) == "log";
  node.require("sampling", !p.log || p.lower > 0, "log sampling needs a range with lower > 0");
  node.reject_unknown_keys();
  return p;
}

// `name: {unknown: true, initial, positive | bounds, true, lr}` (solvers/core/unknowns.h).
UnknownConstant read_unknown_constant(const io::ConfigNode& node, const std::string& name) {
  if (!node.get_or("unknown", false)) {
    if (node.has("true"))
      throw node.error("true", "'true' is the truth of an unknown constant; '" + name +
                                   "' is known (give unknown: true, or the value itself)");
    throw node.error("unknown", "a known constant is a number or an expression; a mapping declares an "
                                "unknown one: {unknown: true, initial: …}");
  }
  UnknownConstant u;
  u.name = name;
  u.initial = node.get<double>("initial");
  u.positive = node.get_or("positive", false);
  if (node.has("bounds")) {
    const std::vector<double> b = node.get_list<double>("bounds", 2);
    u.bounds = std::make_pair(b[0], b[1]);
    node.require("bounds", b[0] < b[1], "expected [lower, upper] with lower < upper");
    node.require("positive", !u.positive, "give positive or bounds, not both");
    node.require("initial", u.initial > b[0] && u.initial < b[1],
                 "expected an initial value strictly inside bounds [" + io::format_number(b[0]) + ", " +
                     io::format_number(b[1]) + "]");
  }
  node.require("initial", std::isfinite(u.initial) && (!u.positive || u.initial > 0),
               u.positive ? "expected an initial value > 0 (positive: true)" : "expected a finite initial value");
  if (node.has("true")) {
    u.truth = node.get<double>("true");
    node.require("true", std::isfinite(*u.truth), "expected a finite number");
  }
  if (node.has("lr")) {
    u.lr = node.get<double>("lr");
    node.require("lr", *u.lr > 0, "expected a learning rate > 0");
  }
  node.reject_unknown_keys();
  return u;
}

}  // namespace nfield::solvers
