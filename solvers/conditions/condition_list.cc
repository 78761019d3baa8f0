// SPDX-License-Identifier: MIT
#include "solvers/conditions/condition_list.h"

#include <algorithm>

#include "io/text.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/geometry/geometry_config.h"

namespace nfield::solvers {

namespace {

bool is_initial(const io::ConfigNode& item) {
  return item.has("on") && !item.has_list("on") && io::to_lower(item.get<std::string>("on")) == "initial";
}

const char* type_name(ConditionType type) {
  switch (type) {
    case ConditionType::kDirichlet: return "dirichlet";
    case ConditionType::kNeumann: return "Neumann";
    case ConditionType::kRobin: return "Robin";
    case ConditionType::kPeriodic: return "periodic";
    case ConditionType::kResidual: return "residual";
    case ConditionType::kInitialValue: return "initial value";
    case ConditionType::kInitialVelocity: return "initial velocity";
  }
  return "";
}

int output_index(const std::vector<std::string>& outputs, const std::string& name) {
  const auto at = std::find(outputs.begin(), outputs.end(), name);
  return at == outputs.end() ? -1 : static_cast<int>(at - outputs.begin());
}

// `type` and `on`: the item's kind and where it holds.
void read_where(const io::ConfigNode& item, const Domain& domain, const ConditionReading& reading,
                ConditionItem& c) {
  c.initial = is_initial(item);
  if (c.initial) {
    if (!domain.has_time()) throw item.error("on", "'initial' needs a domain with a time interval");
    std::vector<std::string> types{"value", "velocity"};
    if (reading.allow_residual) types.push_back("residual");
    const std::string type = item.get_choice("type", types);
    c.type = type == "value"      ? ConditionType::kInitialValue
             : type == "velocity" ? ConditionType::kInitialVelocity
                                  : ConditionType::kResidual;
    return;
  }
  std::vector<std::string> types{"dirichlet", "neumann", "robin", "periodic"};
  if (reading.allow_residual) types.push_back("residual");
  const std::string type = item.get_choice("type", types);
  c.type = type == "dirichlet"  ? ConditionType::kDirichlet
           : type == "neumann"  ? ConditionType::kNeumann
           : type == "robin"    ? ConditionType::kRobin
           : type == "periodic" ? ConditionType::kPeriodic
                                : ConditionType::kResidual;
  if (domain.geometry()) {
    if (c.type == ConditionType::kPeriodic)
      throw item.error("type", "a periodic condition pairs faces of a box domain; this domain has a geometry");
    // `on` is required, as on a box: a part, a non-empty list of parts, or boundary.
    if (item.has_list("on"))
      item.require("on", !item.get<std::vector<std::string>>("on").empty(),
                   "expected a part name or a non-empty list of part names");
    else
      (void)item.get<std::string>("on");
    c.parts = geometry::read_selection(item, *domain.geometry());
    if (c.hard && c.parts->where)
      throw item.error("where", "a hard condition holds on whole parts (its φ is the distance to them); "
                                "name the parts in `on` or use enforce: soft");
    return;
  }
  c.faces = condition_faces(item, domain);
  if (c.type == ConditionType::kPeriodic) {
    std::vector<Face>& f = c.faces;
    if (f.size() != 2 || f[0].axis != f[1].axis || f[0].upper == f[1].upper) {
      std::vector<std::string> names;
      for (const Face& face : f) names.push_back(face.name());
      throw item.error("on", "a periodic condition pairs two opposite faces of one axis (e.g. [x_min, "
                             "x_max]); got " + io::join(names));
    }
    if (f[0].upper) std::swap(f[0], f[1]);
  }
}

// `value`: one expression (the first output, the others 0), a list (one per output) or a
// mapping from output names (the others free).
void read_values(const io::ConfigNode& item, const Domain& domain, const ConditionReading& reading,
                 ConditionItem& c) {
  const int n = static_cast<int>(reading.outputs.size());
  c.values.assign(static_cast<std::size_t>(n), std::nullopt);
  if (!item.has_map("value")) {
    const std::vector<io::Expression> all = channel_expressions(item, "value", domain, n, reading.constants);
    for (int k = 0; k < n; ++k) {
      c.outputs.push_back(k);
      c.values[static_cast<std::size_t>(k)] = all[static_cast<std::size_t>(k)];
    }
    return;
  }
  const io::ConfigNode map = item.child("value");
  map.require(map.size() > 0, "expected output: expression entries (outputs: " + io::join(reading.outputs) + ")");
  for (const std::string& key : map.keys())
    if (output_index(reading.outputs, key) < 0)
      throw map.error(key, "'" + key + "' is no output (outputs: " + io::join(reading.outputs) + ")");
  for (int k = 0; k < n; ++k) {
    const std::string& name = reading.outputs[static_cast<std::size_t>(k)];
    if (!map.has(name)) continue;
    c.outputs.push_back(k);
    c.values[static_cast<std::size_t>(k)] = map.get_expression(name, domain.expression_variables(), reading.constants);
  }
}

// Periodic `outputs`: names of the outputs tied (default all).
void read_periodic_outputs(const io::ConfigNode& item, const ConditionReading& reading, ConditionItem& c) {
  if (!item.has("outputs")) {
    for (int k = 0; k < static_cast<int>(reading.outputs.size()); ++k) c.outputs.push_back(k);
    return;
  }
  const auto names = item.get<std::vector<std::string>>("outputs");
  item.require("outputs", !names.empty(), "expected a non-empty list of output names");
  for (int k = 0; k < static_cast<int>(reading.outputs.size()); ++k)
    if (std::count(names.begin(), names.end(), reading.outputs[static_cast<std::size_t>(k)]) > 0)
      c.outputs.push_back(k);
  for (const std::string& name : names)
    if (output_index(reading.outputs, name) < 0)
      throw item.error("outputs", "'" + name + "' is no output (outputs: " + io::join(reading.outputs) + ")");
}

ConditionItem read_item(const io::ConfigNode& item, std::size_t index, const Domain& domain,
                        const ConditionReading& reading) {
  ConditionItem c(item);
  c.index = index;
  item.require(item.is_map(), "expected a condition {on, type, value, …}");
  c.hard = item.get_choice("enforce", {"soft", "hard"}, "soft") == "hard";
  if (c.hard && !reading.allow_hard)
    throw item.error("enforce", "this problem does not support enforce: hard (poisson, pde and "
                                "wave do); use enforce: soft");
  if (c.hard) {
    item.require("weight", !item.has("weight"), "a hard condition (enforce: hard) is no loss term and takes no weight");
  } else {
    c.weight = item.get_or("weight", 1.0);
    item.require("weight", c.weight >= 0, "expected a weight >= 0");
  }
  read_where(item, domain, reading, c);
  if (c.hard && c.type != ConditionType::kDirichlet && c.type != ConditionType::kInitialValue &&
      c.type != ConditionType::kInitialVelocity)
    throw item.error("enforce", std::string("a ") + type_name(c.type) +
                                    " condition cannot be hard (only dirichlet and initial "
                                    "value/velocity can); use enforce: soft");
  if (c.type == ConditionType::kPeriodic) {
    read_periodic_outputs(item, reading, c);
  } else if (c.type == ConditionType::kResidual) {
    c.residual = item.get<std::string>("residual");
  } else {
    read_values(item, domain, reading, c);
    if (c.hard && c.outputs.size() != reading.outputs.size())
      throw item.error("value", "a hard condition gives every output a value (outputs: " +
                                    io::join(reading.outputs) + "); name them all or use enforce: soft");
  }
  if (c.type == ConditionType::kRobin) {
    c.robin_a = item.get_expression("a", domain.expression_variables(), reading.constants);
    c.robin_b = item.get_expression("b", domain.expression_variables(), reading.constants);
  }
  if (c.hard && c.type == ConditionType::kInitialValue && item.has("time_scale"))
    c.time_scale = item.get_positive<double>("time_scale");
  if (item.has("fade")) {
    item.require("fade", c.hard && c.type == ConditionType::kDirichlet && c.parts,
                 "`fade` belongs to a hard Dirichlet condition on parts of a domain.geometry");
    c.fade = item.get_positive<double>("fade");
  }
  if (item.has("saturate")) {
    item.require("saturate", c.hard && c.type == ConditionType::kDirichlet && c.parts,
                 "`saturate` belongs to a hard Dirichlet condition on parts of a domain.geometry");
    c.saturate = item.get_positive<double>("saturate");
  }
  item.reject_unknown_keys();
  return c;
}

}  // namespace

std::vector<io::Expression> ConditionItem::channel_values(const Domain& domain) const {
  std::vector<io::Expression> out;
  for (const auto& v : values) out.push_back(v ? *v : io::Expression("0", domain.expression_variables()));
  return out;
}

std::vector<ConditionItem> read_conditions(const io::ConfigNode& conditions, const Domain& domain,
                                           const ConditionReading& reading) {
  std::vector<ConditionItem> items;
  if (conditions.is_null()) return items;
  conditions.require(conditions.is_sequence(), "expected a list of conditions");
  for (std::size_t i = 0; i < conditions.size(); ++i)
    items.push_back(read_item(conditions.at(i), i, domain, reading));
  return items;
}

}  // namespace nfield::solvers
