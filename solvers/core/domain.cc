// SPDX-License-Identifier: MIT
#include "solvers/core/domain.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "io/registry.h"
#include "solvers/geometry/geometry.h"
#include "solvers/geometry/geometry_config.h"

namespace nfield::solvers {
namespace {
const char* const kAxes[] = {"x", "y", "z"};
}

void DomainParameter::validate() const {
  if (!(std::isfinite(lower) && std::isfinite(upper) && lower < upper))
    throw std::invalid_argument("parameter '" + name + "': range [" + std::to_string(lower) + ", " +
                                std::to_string(upper) + "] must be finite with lower < upper");
  if (log && !(lower > 0))
    throw std::invalid_argument("parameter '" + name + "': log sampling needs lower > 0, got " +
                                std::to_string(lower));
}

double DomainParameter::at(double u) const {
  if (log) return std::exp(std::log(lower) + u * (std::log(upper) - std::log(lower)));
  return lower + u * (upper - lower);
}

std::string Face::name() const { return std::string(kAxes[axis]) + (upper ? "_max" : "_min"); }

Domain::Domain(std::vector<double> lower, std::vector<double> upper,
               std::optional<std::pair<double, double>> time)
    : lower_(std::move(lower)), upper_(std::move(upper)), time_(time) {
  if (lower_.empty() || lower_.size() > 3 || lower_.size() != upper_.size())
    throw std::invalid_argument("domain: lower and upper need the same length, 1 to 3");
  for (size_t i = 0; i < lower_.size(); ++i)
    if (!(upper_[i] > lower_[i]))
      throw std::invalid_argument("domain: upper[" + std::to_string(i) + "] must exceed lower");
  if (time_ && !(time_->second > time_->first))
    throw std::invalid_argument("domain: time interval must be increasing");
}

namespace {
std::vector<double> geometry_corner(const std::shared_ptr<const geometry::Geometry>& g, bool upper) {
  if (!g) throw std::invalid_argument("domain: no geometry");
  const geometry::Bounds b = g->bounds();
  std::vector<double> v;
  for (int a = 0; a < g->dim(); ++a) v.push_back(upper ? b.upper(a) : b.lower(a));
  return v;
}
}  // namespace

Domain::Domain(std::shared_ptr<const geometry::Geometry> geometry, std::optional<std::pair<double, double>> time)
    : Domain(geometry_corner(geometry, false), geometry_corner(geometry, true), time) {
  geometry_ = std::move(geometry);
}

void Domain::require_box(const char* what) const {
  if (geometry_)
    throw std::logic_error(std::string("Domain::") + what +
                           ": a domain with a geometry has parts, not box faces (sample_boundary)");
}

namespace {
std::optional<std::pair<double, double>> read_time(const io::ConfigNode& node) {
  if (!node.has("time")) return std::nullopt;
  const auto t = node.get_list<double>("time", 2);
  node.require("time", t[1] > t[0], "expected [t0, t1] with t1 > t0");
  return std::pair{t[0], t[1]};
}
}  // namespace

Domain Domain::from_config(const io::ConfigNode& node, const std::filesystem::path& config_dir) {
  if (!node.has("geometry")) return from_config(node);
  for (const char* key : {"lower", "upper"})
    node.require(key, !node.has(key), std::string("a domain with a geometry takes no `") + key +
                                          "` (the geometry's bounding box is its box)");
  auto g = std::make_shared<const geometry::Geometry>(geometry::read_geometry(node.child("geometry"), config_dir));
  const auto time = read_time(node);
  try {
    return Domain(std::move(g), time);
  } catch (const std::invalid_argument& e) {
    // A bounding box that rounding made flat (coordinates of 1e300 and a radius of 1).
    throw node.error("geometry", std::string("the geometry's bounding box is not a box: ") + e.what());
  }
}

Domain Domain::box_3d_from_config(const io::ConfigNode& root, const std::string& what) {
  if (!root.has("domain")) return Domain({-1, -1, -1}, {1, 1, 1});
  const io::ConfigNode node = root.child("domain");
  Domain domain = from_config(node);
  if (domain.has_time()) throw node.error("time", what + " has no time axis");
  if (domain.space_dim() != 3) throw node.error("lower", what + " needs a 3D domain");
  return domain;
}

Domain Domain::from_config(const io::ConfigNode& node) {
  node.require("geometry", !node.has("geometry"),
               "this problem takes a box domain (lower, upper); shapes (domain.geometry) work with "
               "problem: poisson and problem: pde");
  const auto lower = node.get<std::vector<double>>("lower");
  node.require("lower", !lower.empty() && lower.size() <= 3, "expected a list of 1 to 3 numbers");
  const auto upper = node.get_list<double>("upper", lower.size());
  for (size_t i = 0; i < lower.size(); ++i)
    node.require("upper", upper[i] > lower[i],
                 "upper[" + std::to_string(i) + "] must be greater than lower[" +
                     std::to_string(i) + "]");
  return Domain(lower, upper, read_time(node));
}

void Domain::add_parameter(DomainParameter parameter) {
  parameter.validate();
  const std::vector<std::string> names = input_names();
  if (std::find(names.begin(), names.end(), parameter.name) != names.end() || parameter.name == "x" ||
      parameter.name == "y" || parameter.name == "z" || parameter.name == "t")
    throw std::invalid_argument("parameter '" + parameter.name + "': the name is taken by an input");
  parameters_.push_back(std::move(parameter));
}

int Domain::parameter_index(const std::string& name) const {
  for (int k = 0; k < parameter_count(); ++k)
    if (parameters_[static_cast<std::size_t>(k)].name == name) return k;
  return -1;
}

Eigen::VectorXd Domain::parameter_middles() const {
  Eigen::VectorXd v(parameter_count());
  for (int k = 0; k < parameter_count(); ++k) v(k) = parameters_[static_cast<std::size_t>(k)].middle();
  return v;
}

void Domain::map_parameters(Eigen::MatrixXd& x) const {
  for (int k = 0; k < parameter_count(); ++k) {
    const DomainParameter& p = parameters_[static_cast<std::size_t>(k)];
    for (Eigen::Index r = 0; r < x.rows(); ++r) x(r, parameter_column(k)) = p.at(x(r, parameter_column(k)));
  }
}

void Domain::draw_parameters(Random& rng, Eigen::MatrixXd& x) const {
  if (parameters_.empty()) return;
  x.rightCols(parameter_count()) = unit_points(rng, x.rows(), parameter_count());
  map_parameters(x);
}

Eigen::VectorXd Domain::input_lower() const {
  Eigen::VectorXd v(input_dim());
  for (int i = 0; i < space_dim(); ++i) v(i) = lower_[i];
  if (has_time()) v(time_column()) = time_->first;
  for (int k = 0; k < parameter_count(); ++k) v(parameter_column(k)) = parameters_[static_cast<std::size_t>(k)].lower;
  return v;
}

Eigen::VectorXd Domain::input_upper() const {
  Eigen::VectorXd v(input_dim());
  for (int i = 0; i < space_dim(); ++i) v(i) = upper_[i];
  if (has_time()) v(time_column()) = time_->second;
  for (int k = 0; k < parameter_count(); ++k) v(parameter_column(k)) = parameters_[static_cast<std::size_t>(k)].upper;
  return v;
}

std::vector<std::string> Domain::input_names() const {
  std::vector<std::string> names(kAxes, kAxes + space_dim());
  if (has_time()) names.push_back("t");
  for (const DomainParameter& p : parameters_) names.push_back(p.name);
  return names;
}

std::vector<std::string> Domain::expression_variables() const {
  std::vector<std::string> names = input_names();
  for (const char* v : {"x", "y", "z", "t"})
    if (std::find(names.begin(), names.end(), v) == names.end()) names.push_back(v);
  return names;
}

std::vector<Face> Domain::faces() const {
  std::vector<Face> out;
  for (int a = 0; a < space_dim(); ++a) {
    out.push_back({a, false});
    out.push_back({a, true});
  }
  return out;
}

Face Domain::face(const std::string& name) const {
  require_box("face");
  Registry<Face> names("face");
  for (const Face& f : faces()) names.add(f.name(), f);
  return names.at(name);
}

Eigen::MatrixXd Domain::sample_interior(Random& rng, Eigen::Index n) const {
  if (geometry_) {
    Eigen::MatrixXd x(n, input_dim());
    x.leftCols(space_dim()) = geometry_->sample_interior(rng, n);
    if (has_time())
      x.col(time_column()) = time_->first + (time_->second - time_->first) * unit_points(rng, n, 1).col(0).array();
    draw_parameters(rng, x);
    return x;
  }
  const Eigen::VectorXd lo = input_lower(), hi = input_upper();
  Eigen::MatrixXd x = unit_points(rng, n, input_dim());
  for (int c = 0; c < coordinate_dim(); ++c) x.col(c) = lo(c) + (hi(c) - lo(c)) * x.col(c).array();
  map_parameters(x);
  return x;
}

Eigen::MatrixXd Domain::sample_interior_where(Random& rng, Eigen::Index n, const io::Expression& where) const {
  constexpr Eigen::Index kGiveUp = 1'000'000;
  Eigen::MatrixXd out(n, input_dim());
  Eigen::Index have = 0, drawn = 0, missed = 0;
  double rate = 1;
  while (have < n) {
    if (missed >= kGiveUp)
      throw std::runtime_error("the region '" + where.text() + "' is empty: none of " + std::to_string(missed) +
                               " points drawn in the domain lies in it");
    const Eigen::Index m = std::max<Eigen::Index>(64, static_cast<Eigen::Index>(1.2 * (n - have) / rate) + 16);
    const Eigen::MatrixXd x = sample_interior(rng, m);
    const Eigen::VectorXd keep = where.evaluate(x);
    Eigen::Index hits = 0;
    for (Eigen::Index r = 0; r < m && have < n; ++r)
      if (keep(r) != 0) {
        out.row(have++) = x.row(r);
        ++hits;
      }
    drawn += m;
    missed = hits > 0 ? 0 : missed + m;
    rate = std::max(static_cast<double>(have) / static_cast<double>(drawn), 1e-3);
  }
  return out;
}

std::shared_ptr<const io::Expression> read_interior_region(const io::ConfigNode& node, std::string_view key,
                                                           const Domain& domain, io::ExpressionConstants constants) {
  auto region = std::make_shared<const io::Expression>(
      node.get_expression(key, domain.expression_variables(), std::move(constants)));
  Random probe(1);
  const Eigen::VectorXd hit = region->evaluate(domain.sample_interior(probe, 1 << 14));
  node.require(key, (hit.array() != 0).any(), "no point of 2^14 drawn in the domain lies in this region");
  return region;
}

Eigen::MatrixXd Domain::sample_face(const Face& face, Random& rng, Eigen::Index n) const {
  require_box("sample_face");
  Eigen::MatrixXd x = sample_interior(rng, n);
  x.col(face.axis).setConstant(face.upper ? upper_[face.axis] : lower_[face.axis]);
  return x;
}

double Domain::face_measure(const Face& face) const {
  double m = 1;
  for (int a = 0; a < space_dim(); ++a)
    if (a != face.axis) m *= upper_[a] - lower_[a];
  return m;
}

Eigen::MatrixXd Domain::sample_faces(const std::vector<Face>& faces, Random& rng,
                                     Eigen::Index n) const {
  require_box("sample_faces");
  if (faces.empty()) throw std::invalid_argument("Domain::sample_faces: no faces");
  std::vector<double> cumulative;
  double total = 0;
  for (const Face& f : faces) cumulative.push_back(total += face_measure(f));
  // Column input_dim picks the face. From the engine it is drawn after all the points,
  // the order uniform runs have always used.
  Eigen::MatrixXd x;
  Eigen::VectorXd pick(n);
  if (rng.sequence()) {
    const Eigen::MatrixXd u = unit_points(rng, n, input_dim() + 1);
    x = u.leftCols(input_dim());
    pick = u.col(input_dim());
  } else {
    x = unit_points(rng, n, input_dim());
    for (Eigen::Index r = 0; r < n; ++r) pick(r) = uniform01(rng);
  }
  const Eigen::VectorXd lo = input_lower(), hi = input_upper();
  for (int c = 0; c < coordinate_dim(); ++c) x.col(c) = lo(c) + (hi(c) - lo(c)) * x.col(c).array();
  map_parameters(x);
  for (Eigen::Index r = 0; r < n; ++r) {
    const double u = pick(r) * total;
    size_t k = 0;
    while (k + 1 < faces.size() && u >= cumulative[k]) ++k;
    x(r, faces[k].axis) = faces[k].upper ? upper_[faces[k].axis] : lower_[faces[k].axis];
  }
  return x;
}

Eigen::MatrixXd Domain::sample_initial(Random& rng, Eigen::Index n) const {
  if (geometry_) {
    Eigen::MatrixXd x(n, input_dim());
    x.leftCols(space_dim()) = geometry_->sample_interior(rng, n);
    if (has_time()) x.col(time_column()).setConstant(time_->first);
    draw_parameters(rng, x);
    return x;
  }
  if (rng.sequence() && has_time()) {
    // Only the space coordinates vary on the slice: no sequence dimension spent on t.
    Eigen::MatrixXd x(n, input_dim());
    x.leftCols(space_dim()) = unit_points(rng, n, space_dim());
    for (int c = 0; c < space_dim(); ++c)
      x.col(c) = lower_[c] + (upper_[c] - lower_[c]) * x.col(c).array();
    x.col(time_column()).setConstant(time_->first);
    draw_parameters(rng, x);
    return x;
  }
  Eigen::MatrixXd x = sample_interior(rng, n);
  if (has_time()) x.col(time_column()).setConstant(time_->first);
  return x;
}

Eigen::VectorXd Domain::normal(const Face& face) const {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(input_dim());
  v(face.axis) = face.upper ? 1.0 : -1.0;
  return v;
}

Domain::BoundaryPoints Domain::sample_boundary(const geometry::Selection& selection, Random& rng,
                                               Eigen::Index n) const {
  if (!geometry_) throw std::logic_error("Domain::sample_boundary: a box domain samples faces (sample_faces)");
  const geometry::BoundarySample s = geometry_->sample_boundary(rng, n, selection);
  BoundaryPoints out{Eigen::MatrixXd::Zero(n, input_dim()), Eigen::MatrixXd::Zero(n, input_dim()), s.parts};
  out.points.leftCols(space_dim()) = s.points;
  out.normals.leftCols(space_dim()) = s.normals;
  if (has_time())
    out.points.col(time_column()) =
        time_->first + (time_->second - time_->first) * unit_points(rng, n, 1).col(0).array();
  draw_parameters(rng, out.points);
  return out;
}

geometry::Measure Domain::space_measure() const {
  if (geometry_) return geometry_->volume();
  double v = 1;
  for (int a = 0; a < space_dim(); ++a) v *= upper_[static_cast<size_t>(a)] - lower_[static_cast<size_t>(a)];
  return {v, 0, true};
}

Eigen::Array<bool, Eigen::Dynamic, 1> Domain::contains_rows(const Eigen::MatrixXd& points) const {
  if (!geometry_) return Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(points.rows(), true);
  return geometry_->contains_rows(points.leftCols(space_dim()));
}

Eigen::MatrixXd Domain::boundary_normals(const Eigen::MatrixXd& points) const {
  if (!geometry_) throw std::logic_error("Domain::boundary_normals: a box domain has face normals (normal)");
  Eigen::MatrixXd n = Eigen::MatrixXd::Zero(points.rows(), input_dim());
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    geometry::Vec3 x = geometry::Vec3::Zero();
    for (int a = 0; a < space_dim(); ++a) x(a) = points(r, a);
    const geometry::Vec3 v = geometry_->normal(x);
    for (int a = 0; a < space_dim(); ++a) n(r, a) = v(a);
  }
  return n;
}

}  // namespace nfield::solvers
