// SPDX-License-Identifier: MIT
#include "solvers/problems/drawn_family.h"

#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "io/text.h"
#include "solvers/core/problem_capabilities.h"

namespace nfield::solvers {
namespace {

// A key drawn as a sine series (drawn_family.h) on the domain's box.
struct SeriesSettings {
  int modes = 6;
  double decay = 2, scale = 1;
  std::string solution;  // the equation key that gets u; empty: none
  std::vector<double> lower, upper;
};

// One drawn key: a number, a list of numbers (each component its own range), or a series.
struct DrawnKey {
  std::string key;
  bool list = false;
  std::vector<double> lower, upper;
  std::optional<SeriesSettings> series;
};

SeriesSettings read_series(const io::ConfigNode& item, const io::ConfigNode& root) {
  const io::ConfigNode node = item.child("sine_series");
  SeriesSettings s;
  if (node.has("modes")) s.modes = node.get_in_range("modes", 1, 32);
  if (node.has("decay")) s.decay = node.get_in_range("decay", 0.0, 20.0);
  if (node.has("scale")) s.scale = node.get_in_range("scale", 0.0, 1e12);
  if (node.has("solution")) {
    s.solution = node.get<std::string>("solution");
    node.require("solution", io::is_name(s.solution, true), "expected an equation key (a name: exact)");
  }
  node.reject_unknown_keys();
  const YAML::Node& domain = root.yaml()["domain"];
  if (!domain || !domain.IsMap() || !domain["lower"] || !domain["upper"] || !domain["lower"].IsSequence())
    throw item.error("sine_series", "expected a box domain (domain.lower, domain.upper): the series' modes are the box's");
  try {
    s.lower = domain["lower"].as<std::vector<double>>();
    s.upper = domain["upper"].as<std::vector<double>>();
  } catch (const YAML::Exception&) {
    throw item.error("sine_series", "expected a box domain whose lower and upper are lists of numbers");
  }
  item.require("sine_series", !s.lower.empty() && s.lower.size() <= 3 && s.lower.size() == s.upper.size(),
               "expected a box domain of 1 to 3 space axes");
  for (std::size_t i = 0; i < s.lower.size(); ++i)
    item.require("sine_series", std::isfinite(s.lower[i]) && std::isfinite(s.upper[i]) && s.lower[i] < s.upper[i],
                 "expected a box domain with lower < upper on every axis");
  double terms = 1;
  for (std::size_t i = 0; i < s.lower.size(); ++i) terms *= s.modes;
  item.require("sine_series", terms <= 4096, "expected at most 4096 terms (modes^dimensions)");
  return s;
}

DrawnKey read_drawn_key(const io::ConfigNode& draw, const std::string& key, const io::ConfigNode& root) {
  const io::ConfigNode item = draw.child(key);
  DrawnKey d;
  d.key = key;
  item.expect_keys({"range", "sine_series"});
  if (item.has("sine_series")) {
    item.require("sine_series", !item.has("range"), "expected range or sine_series, not both");
    d.series = read_series(item, root);
    return d;
  }
  const io::ConfigNode range = item.child("range");
  range.require(range.is_sequence() && range.size() == 2, "expected [lower, upper]: two numbers, or two lists");
  const io::ConfigNode low = range.at(0), high = range.at(1);
  d.list = low.is_sequence();
  if (d.list) {
    d.lower = low.as<std::vector<double>>();
    d.upper = high.as<std::vector<double>>();
    range.require(!d.lower.empty() && d.lower.size() == d.upper.size(),
                  "expected [[lower…], [upper…]] of one length (one range per component)");
  } else {
    d.lower = {low.as<double>()};
    d.upper = {high.as<double>()};
  }
  for (std::size_t i = 0; i < d.lower.size(); ++i) {
    range.require(std::isfinite(d.lower[i]) && std::isfinite(d.upper[i]), "expected finite bounds");
    range.require(d.lower[i] <= d.upper[i], "expected lower <= upper (component " + std::to_string(i) + ": " +
                                                io::format_number(d.lower[i]) + " > " +
                                                io::format_number(d.upper[i]) + ")");
  }
  return d;
}

struct Settings {
  std::vector<DrawnKey> keys;
  int instances = 8, held_out = 0;
  std::uint64_t seed = 0;
};

Settings read_settings(const io::ConfigNode& root) {
  const io::ConfigNode equation = root.child("equation");
  const io::ConfigNode family = equation.child("family");
  Settings s;
  const io::ConfigNode draw = family.child("draw");
  draw.require(draw.is_map() && draw.size() > 0, "expected a mapping of equation keys to {range: [lower, upper]}");
  for (const std::string& key : draw.keys()) {
    draw.require(key, key != "family", "expected an equation key other than family");
    if (equation.yaml()[key])
      throw draw.error(key, "equation." + key + " is set too: a drawn key takes its value from its range alone");
    s.keys.push_back(read_drawn_key(draw, key, root));
    const auto& series = s.keys.back().series;
    if (series && !series->solution.empty()) {
      const std::string& solution = series->solution;
      const io::ConfigNode item = draw.child(key).child("sine_series");
      item.require("solution", solution != "family" && solution != key && !draw.yaml()[solution],
                   "expected an equation key neither drawn nor family");
      if (equation.yaml()[solution])
        throw item.error("solution", "equation." + solution + " is set too: the series' solution takes its place");
    }
  }
  s.instances = family.has("instances") ? family.get_in_range("instances", 1, 100000) : s.instances;
  s.held_out = family.has("held_out") ? family.get_in_range("held_out", 0, 100000) : s.held_out;
  if (family.has("seed")) s.seed = static_cast<std::uint64_t>(family.get_in_range("seed", 0L, 1L << 40));
  family.reject_unknown_keys();
  return s;
}

// An instance: its drawn values by key, and the same as metrics (KEY or KEY_i).
struct Draw {
  std::vector<std::pair<std::string, YAML::Node>> yaml;
  std::vector<std::pair<std::string, double>> values;
};

std::vector<Draw> draw_all(const Settings& s) {
  std::mt19937_64 engine(s.seed ^ 0xFA111E5ull);
  std::vector<Draw> draws(static_cast<std::size_t>(s.instances + s.held_out));
  for (Draw& d : draws)
    for (const DrawnKey& key : s.keys) {
      if (key.series) {
        const SeriesSettings& series = *key.series;
        const SineSeriesDraw drawn =
            draw_sine_series(series.lower, series.upper, series.modes, series.decay, series.scale, engine);
        d.yaml.emplace_back(key.key, YAML::Node(drawn.field));
        if (!series.solution.empty()) d.yaml.emplace_back(series.solution, YAML::Node(drawn.solution));
        continue;
      }
      YAML::Node node;
      for (std::size_t i = 0; i < key.lower.size(); ++i) {
        const double u = static_cast<double>(engine() >> 11) * 0x1.0p-53;
        const double v = key.lower[i] + (key.upper[i] - key.lower[i]) * u;
        if (key.list) node.push_back(v);
        else node = v;
        d.values.emplace_back(key.list ? key.key + "_" + std::to_string(i) : key.key, v);
      }
      d.yaml.emplace_back(key.key, node);
    }
  return draws;
}

class DrawnFamily final : public Problem, public HasInstances {
 public:
  DrawnFamily(const ProblemContext& context, ProblemFactory factory) : context_(context), factory_(std::move(factory)) {
    const io::ConfigNode equation = context.root.child("equation");
    const Settings settings = read_settings(context.root);
    // The equation's other keys are read (and unknown ones refused) by each instance's own
    // factory, on its copy, whose reads count in this tree (ConfigNode::with_yaml).
    draw_ = equation.child("family").child("draw");
    draws_ = draw_all(settings);
    training_ = settings.instances;
    first_ = build(0);
    // Every instance once, so that a drawn value its problem refuses is an error at load, not
    // after training.
    for (int k = 1; k < static_cast<int>(draws_.size()); ++k) (void)build(k);
    if (first_->ansatz())
      throw equation.error("family", "a family's instances take soft conditions only (no type: dirichlet_hard …)");
    if (first_->unknowns())
      throw equation.error("family", "a family's instances have no unknown constants (inverse problems are one signal)");
  }

  const Domain& domain() const override { return first_->domain(); }
  int field_input_dim() const override { return first_->field_input_dim(); }
  int output_dim() const override { return first_->output_dim(); }
  std::vector<std::string> output_names() const override { return first_->output_names(); }
  fields::SineFrequencies default_sine_frequencies() const override { return first_->default_sine_frequencies(); }
  std::vector<LossTerm> loss_terms() const override { return first_->loss_terms(); }
  int residual_term() const override { return first_->residual_term(); }
  bool has_exact() const override { return first_->has_exact(); }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override { return first_->exact(x); }
  bool writes_grid_outputs() const override { return first_->writes_grid_outputs(); }
  void write_outputs(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const override {
    first_->write_outputs(context, metrics);
  }

  std::vector<ProblemInstance> instances(bool held_out) const override {
    std::vector<ProblemInstance> list;
    const int begin = held_out ? training_ : 0, end = held_out ? static_cast<int>(draws_.size()) : training_;
    for (int k = begin; k < end; ++k) {
      ProblemInstance instance{name(k), build(k)};
      instance.values = draws_[static_cast<std::size_t>(k)].values;
      list.push_back(std::move(instance));
    }
    return list;
  }

 private:
  std::string name(int k) const {
    char name[32];
    const bool held_out = k >= training_;
    std::snprintf(name, sizeof name, "%s_%03d", held_out ? "held_out" : "instance", held_out ? k - training_ : k);
    return name;
  }

  std::unique_ptr<Problem> build(int k) const {
    YAML::Node root = YAML::Clone(context_.root.yaml());
    YAML::Node equation = root["equation"];
    equation.remove("family");
    const Draw& draw = draws_[static_cast<std::size_t>(k)];
    for (const auto& [key, value] : draw.yaml) equation[key] = value;
    try {
      return factory_(ProblemContext{context_.root.with_yaml(root), context_.config_dir});
    } catch (const io::ConfigError& e) {
      if (e.line() > 0) throw;
      // At a drawn value, which has no place in the file: reported at its range.
      for (const auto& [key, value] : draw.yaml)
        if (e.key_path() == "equation." + key)
          throw draw_.error(key, name(k) + "'s " + key + " = " + drawn_text(value) + ": " + e.message());
      throw draw_.error(name(k) + ": " + e.key_path() + ": " + e.message());
    }
  }

  // A drawn value as text: a number, [a, b, …], or an expression's head.
  static std::string drawn_text(const YAML::Node& value) {
    if (!value.IsSequence()) {
      double number = 0;
      if (YAML::convert<double>::decode(value, number)) return io::format_number(number);
      const std::string text = value.as<std::string>();
      return text.size() > 40 ? "\"" + text.substr(0, 40) + "…\"" : "\"" + text + "\"";
    }
    std::string text;
    for (std::size_t i = 0; i < value.size(); ++i) text += (i ? ", " : "") + io::format_number(value[i].as<double>());
    return "[" + text + "]";
  }

  ProblemContext context_;
  ProblemFactory factory_;
  io::ConfigNode draw_{YAML::Node(), ""};  // equation.family.draw
  std::vector<Draw> draws_;
  int training_ = 0;
  std::unique_ptr<Problem> first_;
};

}  // namespace

SineSeriesDraw draw_sine_series(const std::vector<double>& lower, const std::vector<double>& upper, int modes,
                                double decay, double scale, std::mt19937_64& engine) {
  static const char* const kAxes[] = {"x", "y", "z"};
  const std::size_t d = lower.size();
  const auto uniform = [&] { return static_cast<double>(engine() >> 11) * 0x1.0p-53; };
  double lowest = 0;  // λ₁: every k_i = 1
  for (std::size_t i = 0; i < d; ++i) lowest += std::pow(std::numbers::pi / (upper[i] - lower[i]), 2);
  std::ostringstream field, solution;
  field.precision(17);
  solution.precision(17);
  std::vector<int> k(d, 1);
  for (bool more = d > 0; more;) {
    double lambda = 0;
    std::ostringstream mode;
    mode.precision(17);
    for (std::size_t i = 0; i < d; ++i) {
      const double w = k[i] * std::numbers::pi / (upper[i] - lower[i]);
      lambda += w * w;
      mode << "*sin(" << w << "*(" << kAxes[i] << "-(" << lower[i] << ")))";
    }
    // Box–Muller from the raw engine: the same draws on every platform.
    const double normal = std::sqrt(-2.0 * std::log(1.0 - uniform())) * std::cos(2.0 * std::numbers::pi * uniform());
    const double c = scale * normal * std::pow(lambda / lowest, -0.5 * decay);
    field << (field.tellp() > 0 ? "+" : "") << "(" << c << ")" << mode.str();
    solution << (solution.tellp() > 0 ? "+" : "") << "(" << -c / lambda << ")" << mode.str();
    more = false;
    for (std::size_t i = 0; i < d && !more; ++i) {
      if (++k[i] <= modes) more = true;
      else k[i] = 1;
    }
  }
  return {field.str(), solution.str()};
}

bool has_drawn_family(const io::ConfigNode& root) {
  const YAML::Node& yaml = root.yaml();
  return yaml.IsMap() && yaml["equation"] && yaml["equation"].IsMap() && yaml["equation"]["family"] &&
         yaml["equation"]["family"].IsMap() && yaml["equation"]["family"]["draw"];
}

std::unique_ptr<Problem> make_drawn_family(const ProblemContext& context, const ProblemFactory& factory) {
  return std::make_unique<DrawnFamily>(context, factory);
}

}  // namespace nfield::solvers
