// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_functionals.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/text.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/geometry/geometry.h"
#include "solvers/geometry/geometry_config.h"
#include "solvers/problems/pde_residual.h"

namespace nfield::solvers {
namespace {

constexpr Eigen::Index kBlock = 4096;  // points per evaluation of the field's streams

// The midpoint rule on box faces: about n nodes shared by measure; a 1-D face is one point.
struct FaceNodes {
  Eigen::MatrixXd points, normals;  // n × space_dim
  Eigen::VectorXd weights;
};
FaceNodes face_nodes(const Domain& domain, const std::vector<Face>& faces, Eigen::Index n) {
  const int d = domain.space_dim();
  const auto measure = [&](const Face& f) {
    double m = 1;
    for (int a = 0; a < d; ++a)
      if (a != f.axis) m *= domain.upper()[static_cast<std::size_t>(a)] - domain.lower()[static_cast<std::size_t>(a)];
    return m;
  };
  double total = 0;
  for (const Face& f : faces) total += measure(f);
  std::vector<Eigen::VectorXd> points, normals;
  std::vector<double> weights;
  for (const Face& f : faces) {
    std::vector<int> axes;
    for (int a = 0; a < d; ++a)
      if (a != f.axis) axes.push_back(a);
    const auto wanted = std::max<Eigen::Index>(1, std::llround(static_cast<double>(n) * measure(f) / total));
    const Eigen::Index side =
        axes.size() <= 1 ? wanted : std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::ceil(std::sqrt(wanted))));
    const Eigen::Index count = axes.empty() ? 1 : axes.size() == 1 ? side : side * side;
    for (Eigen::Index c = 0; c < count; ++c) {
      Eigen::VectorXd x(d), normal = Eigen::VectorXd::Zero(d);
      const auto axis = static_cast<std::size_t>(f.axis);
      x(f.axis) = f.upper ? domain.upper()[axis] : domain.lower()[axis];
      normal(f.axis) = f.upper ? 1 : -1;
      Eigen::Index rest = c;
      for (int a : axes) {
        const auto i = static_cast<std::size_t>(a);
        x(a) = domain.lower()[i] + (domain.upper()[i] - domain.lower()[i]) * (static_cast<double>(rest % side) + 0.5) /
                                       static_cast<double>(side);
        rest /= side;
      }
      points.push_back(x);
      normals.push_back(normal);
      weights.push_back(measure(f) / static_cast<double>(count));
    }
  }
  FaceNodes nodes{Eigen::MatrixXd(static_cast<Eigen::Index>(points.size()), d),
                  Eigen::MatrixXd(static_cast<Eigen::Index>(points.size()), d),
                  Eigen::VectorXd(static_cast<Eigen::Index>(points.size()))};
  for (std::size_t i = 0; i < points.size(); ++i) {
    nodes.points.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
    nodes.normals.row(static_cast<Eigen::Index>(i)) = normals[i].transpose();
    nodes.weights(static_cast<Eigen::Index>(i)) = weights[i];
  }
  return nodes;
}

std::optional<double> read_reference(const io::ConfigNode& item) {
  if (!item.has("reference")) return std::nullopt;
  const auto r = item.get<double>("reference");
  item.require("reference", std::isfinite(r), "expected a finite number");
  return r;
}

}  // namespace

PdeFunctionals::PdeFunctionals(const io::ConfigNode& node, const Domain& domain, const CompileReads& compile,
                               const std::vector<std::string>& taken,
                               std::shared_ptr<const UnknownConstants> unknowns) {
  node.require(node.is_map() && node.size() > 0,
               "expected a mapping of names to functionals ({integral: EXPR, on: PARTS} or {value: EXPR, at: POINTS})");
  std::vector<std::string> normals = {"nx", "ny", "nz"};
  normals.resize(static_cast<std::size_t>(domain.space_dim()));
  for (const std::string& name : node.keys()) {
    const io::ConfigNode item = node.child(name);
    item.require(item.is_map(), "expected a mapping with 'integral' or 'value'");
    const bool integral = item.has("integral"), value = item.has("value");
    item.require(integral != value, "give one of 'integral' (over boundary parts) and 'value' (at points)");
    if (integral)
      for (const std::string& n : normals)
        item.require("integral", std::find(taken.begin(), taken.end(), n) == taken.end(),
                     "the integrand's normal component '" + n + "' is also an output or constant; rename that");
    Nodes nodes = integral ? integral_nodes(item, domain) : value_nodes(item, domain);
    const CompiledReads reads = compile(item, integral ? "integral" : "value", integral ? normals : std::vector<std::string>{});
    Item f;
    f.name = name;
    f.spec = reads.spec;
    f.expression = std::make_shared<const ExpressionResidual>(reads.expression, reads.symbols,
                                                              std::move(nodes.coordinates), unknowns,
                                                              reads.unknown_reads);
    f.inputs = std::move(nodes.inputs);
    f.weights = std::move(nodes.weights);
    f.reference = read_reference(item);
    item.reject_unknown_keys();
    items_.push_back(std::move(f));
  }
}

PdeFunctionals::Nodes PdeFunctionals::integral_nodes(const io::ConfigNode& item, const Domain& domain) {
  item.require(domain.parameter_count() == 0,
               "an integral over a parametric field's domain needs the parameters' values, which functionals do "
               "not take; remove the constants' range or the functional");
  item.require("on", item.has("on"), "missing required key 'on' (parts of the boundary, or faces)");
  const auto count = static_cast<Eigen::Index>(item.get_or("points", 16384));
  item.require("points", count >= 1 && count <= (1 << 22), "expected a number of quadrature nodes in [1, 4194304]");
  Eigen::MatrixXd space, space_normals;
  Eigen::VectorXd weights;
  if (const geometry::Geometry* g = domain.geometry()) {
    const geometry::Selection selection = geometry::read_selection(item, *g);
    geometry::BoundaryQuadrature q = g->boundary_quadrature(selection, count);
    item.require("on", q.weights.size() > 0, "the selected parts have no points on the domain's boundary");
    space = std::move(q.points);
    space_normals = std::move(q.normals);
    weights = std::move(q.weights);
  } else {
    FaceNodes nodes = face_nodes(domain, condition_faces(item, domain), count);
    space = std::move(nodes.points);
    space_normals = std::move(nodes.normals);
    weights = std::move(nodes.weights);
  }
  Nodes f;
  const Eigen::Index n = space.rows(), d = domain.input_dim();
  f.inputs.resize(n, d);
  f.inputs.leftCols(space.cols()) = space;
  if (domain.has_time()) {
    const auto [t0, t1] = domain.time();
    item.require("time", item.has("time"), "an integral on a domain with time needs 'time: T' in [" +
                                               io::format_number(t0) + ", " + io::format_number(t1) + "]");
    const auto t = item.get<double>("time");
    item.require("time", t >= t0 && t <= t1,
                 "expected a time in [" + io::format_number(t0) + ", " + io::format_number(t1) + "]");
    f.inputs.col(domain.time_column()).setConstant(t);
  }
  f.coordinates.resize(n, d + space.cols());
  f.coordinates << f.inputs, space_normals;
  f.weights = std::move(weights);
  return f;
}

PdeFunctionals::Nodes PdeFunctionals::value_nodes(const io::ConfigNode& item, const Domain& domain) {
  const auto d = domain.input_dim();
  const std::string names = io::join(domain.input_names());
  item.require("at", item.has("at") && item.child("at").is_sequence() && item.child("at").size() > 0,
               "expected 'at': a list of points [" + names + "]");
  const io::ConfigNode at = item.child("at");
  Nodes f;
  f.inputs.resize(static_cast<Eigen::Index>(at.size()), d);
  const Eigen::VectorXd lower = domain.input_lower(), upper = domain.input_upper();
  for (std::size_t i = 0; i < at.size(); ++i) {
    const auto p = at.at(i).as<std::vector<double>>();
    at.at(i).require(static_cast<int>(p.size()) == d, "expected a point of " + std::to_string(d) + " numbers [" + names + "]");
    for (int a = 0; a < d; ++a) {
      const double v = p[static_cast<std::size_t>(a)], pad = 1e-9 * (upper(a) - lower(a));
      at.at(i).require(std::isfinite(v) && v >= lower(a) - pad && v <= upper(a) + pad,
                       "the point's " + domain.input_names()[static_cast<std::size_t>(a)] + " = " +
                           io::format_number(v) + " lies outside the domain's [" + io::format_number(lower(a)) + ", " +
                           io::format_number(upper(a)) + "]");
      f.inputs(static_cast<Eigen::Index>(i), a) = v;
    }
  }
  // Points on the boundary count (a pressure on a body's surface): ψ ≥ 0 up to rounding.
  if (const geometry::Geometry* g = domain.geometry()) {
    const int space = domain.space_dim();
    const double tolerance = 1e-9 * (upper.head(space) - lower.head(space)).maxCoeff();
    for (Eigen::Index i = 0; i < f.inputs.rows(); ++i) {
      geometry::Vec3 x = geometry::Vec3::Zero();
      x.head(space) = f.inputs.row(i).head(space).transpose();
      at.at(static_cast<std::size_t>(i)).require(g->distance(x).v >= -tolerance,
                                                 "the point lies outside the domain's geometry");
    }
  }
  f.weights = Eigen::VectorXd::Ones(f.inputs.rows());
  if (item.has("coefficients")) {
    const auto c = item.get<std::vector<double>>("coefficients");
    item.require("coefficients", c.size() == at.size(),
                 "expected one coefficient per point (" + std::to_string(at.size()) + "), got " +
                     std::to_string(c.size()));
    for (std::size_t i = 0; i < c.size(); ++i) {
      item.require("coefficients", std::isfinite(c[i]), "expected finite numbers");
      f.weights(static_cast<Eigen::Index>(i)) = c[i];
    }
  }
  f.coordinates = f.inputs;
  return f;
}

std::vector<std::pair<std::string, double>> PdeFunctionals::values(const OutputContext& context) const {
  std::vector<std::pair<std::string, double>> out;
  for (const Item& f : items_) {
    const autodiff::StreamLayout layout(f.spec);
    double sum = 0;
    Eigen::MatrixXd r;
    for (Eigen::Index first = 0; first < f.inputs.rows(); first += kBlock) {
      const Eigen::Index n = std::min(kBlock, f.inputs.rows() - first);
      const autodiff::Streams<double> streams = context.streams(layout, f.inputs.middleRows(first, n));
      f.expression->evaluate(first, layout, streams, r);
      sum += f.weights.segment(first, n).dot(r.col(0));
    }
    out.emplace_back(f.name, sum);
  }
  return out;
}

void PdeFunctionals::write(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const {
  const auto computed = values(context);
  for (std::size_t k = 0; k < items_.size(); ++k) {
    const auto& [name, value] = computed[k];
    metrics.emplace_back("functional_" + name, value);
    if (const std::optional<double>& ref = items_[k].reference) {
      const double rel = std::abs(value - *ref) / std::max(std::abs(*ref), 1e-300);
      metrics.emplace_back("functional_" + name + "_reference", *ref);
      metrics.emplace_back("functional_" + name + "_rel_error", rel);
      std::printf("functional %s: %.9g (reference %.9g, rel_error %.3e)\n", name.c_str(), value, *ref, rel);
    } else {
      std::printf("functional %s: %.9g\n", name.c_str(), value);
    }
  }
}

}  // namespace nfield::solvers
