// SPDX-License-Identifier: MIT
#include "solvers/geometry/geometry_config.h"

#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>

#include "io/text.h"
#include "solvers/geometry/mesh_shape.h"
#include "solvers/geometry/polygon.h"
#include "solvers/geometry/primitives.h"

namespace nfield::solvers::geometry {
namespace {

const std::vector<std::string> kShapes = {"box",      "disk",    "ball", "ellipse", "ellipsoid",    "polygon",   "cylinder",
                                          "capsule",  "mesh",    "union", "intersection", "difference"};

struct Context {
  std::filesystem::path dir;
  int dim = 0;  // set by the first primitive
  std::map<std::string, io::ConfigNode> names;
};

void set_dim(const io::ConfigNode& n, Context& c, int dim, const std::string& what) {
  if (c.dim == 0) c.dim = dim;
  n.require(c.dim == dim, "a " + std::to_string(dim) + "-D " + what + " in a " + std::to_string(c.dim) + "-D geometry");
}

Vec3 point(const io::ConfigNode& n, const std::string& key, int dim) {
  const auto v = n.get_list<double>(key, static_cast<size_t>(dim));
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < dim; ++i) {
    p(i) = v[static_cast<size_t>(i)];
    n.require(key, std::isfinite(p(i)), "expected finite numbers");
  }
  return p;
}

// A list of 2 or 3 numbers whose length sets the dimension.
int list_dim(const io::ConfigNode& n, const std::string& key) {
  const auto v = n.get<std::vector<double>>(key);
  n.require(key, v.size() == 2 || v.size() == 3, "expected a list of 2 or 3 numbers");
  return static_cast<int>(v.size());
}

std::unique_ptr<Primitive> read_polygon(const io::ConfigNode& n, Context& c) {
  Eigen::MatrixXd v;
  const std::string key = n.has("file") ? "file" : "vertices";
  if (key == "file") {
    n.require(!n.has("vertices"), "give vertices or file, not both");
    try {
      v = read_polygon_file(c.dir / n.get<std::string>("file"));
    } catch (const std::runtime_error& e) {
      throw n.error("file", e.what());
    }
  } else {
    const io::ConfigNode list = n.child("vertices");
    n.require("vertices", list.is_sequence(), "expected a list of [x, y] vertices");
    v.resize(static_cast<Eigen::Index>(list.size()), 2);
    for (size_t i = 0; i < list.size(); ++i) {
      const auto xy = list.at(i).as<std::vector<double>>();
      list.at(i).require(xy.size() == 2, "expected a vertex [x, y]");
      list.at(i).require(std::isfinite(xy[0]) && std::isfinite(xy[1]), "expected a vertex of finite numbers");
      v.row(static_cast<Eigen::Index>(i)) << xy[0], xy[1];
    }
  }
  n.require(key, v.rows() >= 3, "a polygon needs at least 3 vertices, got " + std::to_string(v.rows()));
  try {
    return std::make_unique<Polygon>(v);
  } catch (const std::invalid_argument& e) {
    throw n.error(key, e.what());
  }
}

std::unique_ptr<Primitive> read_primitive(const io::ConfigNode& n, const std::string& shape, Context& c) {
  if (shape == "box") {
    const int dim = list_dim(n, "lower");
    set_dim(n, c, dim, "box");
    const Vec3 lo = point(n, "lower", dim), hi = point(n, "upper", dim);
    for (int i = 0; i < dim; ++i)
      n.require("upper", hi(i) > lo(i),
                "upper[" + std::to_string(i) + "] must be greater than lower[" + std::to_string(i) + "]");
    return std::make_unique<Box>(dim, lo, hi);
  }
  if (shape == "disk" || shape == "ball") {
    const int dim = shape == "disk" ? 2 : 3;
    set_dim(n, c, dim, shape);
    return std::make_unique<Ball>(dim, point(n, "center", dim), n.get_positive<double>("radius"));
  }
  if (shape == "ellipse" || shape == "ellipsoid") {
    const int dim = shape == "ellipse" ? 2 : 3;
    set_dim(n, c, dim, shape);
    const Vec3 axes = point(n, "semi_axes", dim);
    for (int i = 0; i < dim; ++i) n.require("semi_axes", axes(i) > 0, "expected positive semi-axes");
    return std::make_unique<Ellipsoid>(dim, point(n, "center", dim), axes);
  }
  if (shape == "polygon") {
    set_dim(n, c, 2, "polygon");
    return read_polygon(n, c);
  }
  if (shape == "cylinder") {
    set_dim(n, c, 3, "cylinder");
    return std::make_unique<Cylinder>(point(n, "center", 3), n.get_positive<double>("radius"),
                                      n.get_positive<double>("height"));
  }
  if (shape == "capsule") {
    const int dim = list_dim(n, "from");
    set_dim(n, c, dim, "capsule");
    const Vec3 a = point(n, "from", dim), b = point(n, "to", dim);
    n.require("to", (b - a).norm() > 0, "expected an end different from `from`");
    return std::make_unique<Capsule>(dim, a, b, n.get_positive<double>("radius"));
  }
  // mesh
  set_dim(n, c, 3, "mesh");
  const std::filesystem::path path = c.dir / n.get<std::string>("file");
  // ψ: `exact` (the Euclidean distance, C¹) or `smooth` (its quintic spline, spline_distance.h).
  const bool smooth = n.get_choice("distance", {"exact", "smooth"}, std::string("exact")) == "smooth";
  n.require("distance_cells", smooth || !n.has("distance_cells"), "`distance_cells` needs `distance: smooth`");
  const int cells = n.get_or("distance_cells", 64);
  n.require("distance_cells", cells >= 4 && cells <= 512, "expected a whole number of cells from 4 to 512");
  std::unique_ptr<MeshShape> mesh;
  try {
    mesh = read_mesh_shape(path);
  } catch (const std::exception& e) {
    throw n.error("file", e.what());
  }
  if (smooth) mesh->use_spline_distance(cells);
  return mesh;
}

Similarity read_placement(const io::ConfigNode& n, const Context& c) {
  Similarity m;
  if (n.has("scale")) m.scale = n.get_positive<double>("scale");
  if (n.has("rotate")) {
    if (c.dim == 2) {
      const double degrees = n.get<double>("rotate");
      n.require("rotate", std::isfinite(degrees), "expected a finite angle in degrees");
      m.rotation = Similarity::rotation_2d(degrees);
    }
    else {
      m.rotation = Similarity::rotation_3d(point(n, "rotate", 3));
    }
  }
  if (n.has("translate")) m.translation = point(n, "translate", c.dim);
  return m;
}

ShapeTree read_node(const io::ConfigNode& n, Context& c) {
  n.require(n.is_map(), "expected a shape: a mapping with `shape:`");
  const std::string shape = n.get_choice("shape", kShapes);
  ShapeTree tree;
  if (shape == "union" || shape == "intersection" || shape == "difference") {
    const io::ConfigNode list = n.child("shapes");
    n.require("shapes", list.is_sequence() && list.size() >= 2, "expected a list of at least two shapes");
    std::vector<ShapeTree> operands;
    for (size_t i = 0; i < list.size(); ++i) operands.push_back(read_node(list.at(i), c));
    const Combine op = shape == "union" ? Combine::kUnion : shape == "intersection" ? Combine::kIntersection : Combine::kDifference;
    tree = ShapeTree::combine(op, std::move(operands));
  } else {
    std::string name = n.get_or("name", std::string());
    std::unique_ptr<Primitive> p = read_primitive(n, shape, c);
    if (n.has("name")) {
      n.require("name", io::is_name(name, true), "expected a part name of letters, digits and '_', starting with a letter");
      n.require("name", io::to_lower(name) != "boundary", "'boundary' names the whole boundary; pick another name");
      const auto [it, fresh] = c.names.emplace(io::to_lower(name), n);
      n.require("name", fresh, "a part named '" + name + "' exists already");
    }
    tree = ShapeTree::primitive(std::move(name), std::move(p));
  }
  const Similarity m = read_placement(n, c);
  n.reject_unknown_keys();
  return std::move(tree).place(m);
}

}  // namespace

Geometry read_geometry(const io::ConfigNode& node, const std::filesystem::path& config_dir) {
  Context c{config_dir, 0, {}};
  ShapeTree tree = read_node(node, c);
  Geometry g = [&] {
    try {
      return Geometry(std::move(tree));
    } catch (const std::invalid_argument& e) {
      throw node.error(e.what());
    }
  }();
  const Measure v = g.volume(1 << 14);
  node.require(v.exact || v.value > 0,
               "the domain is empty: none of 16384 points drawn in its bounding box lies inside it");
  return g;
}

Selection read_selection(const io::ConfigNode& node, const Geometry& geometry) {
  std::vector<std::string> names;
  if (node.has_list("on")) names = node.get<std::vector<std::string>>("on");
  else names.push_back(node.get_or("on", std::string("boundary")));
  for (const std::string& name : names) {
    if (io::to_lower(name) == "boundary") continue;
    try {
      geometry.part(name);
    } catch (const std::invalid_argument& e) {
      throw node.error("on", e.what());
    }
  }
  const std::string where = node.get_or("where", std::string());
  node.require("where", !node.has("where") || where.find_first_not_of(" \t") != std::string::npos,
               "expected an expression of the coordinates (leave 'where' out for the whole part)");
  std::optional<Selection> selection;
  try {
    selection = geometry.select(names, where);
  } catch (const io::ExpressionError& e) {
    throw node.expression_error("where", e);
  }
  // One point drawn: parts that another shape covers entirely, or a `where` that keeps none of
  // them, are refused here rather than at the first draw of training.
  Random rng(1);
  try {
    (void)geometry.sample_boundary(rng, 1, *selection);
  } catch (const std::runtime_error& e) {
    throw node.error(where.empty() ? "on" : "where", e.what());
  }
  return *selection;
}

}  // namespace nfield::solvers::geometry
