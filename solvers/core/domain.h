// SPDX-License-Identifier: MIT
//
// The domain of a problem: a box [lower, upper] in 1–3 space dimensions, optionally times a
// time interval [t0, t1]. Field inputs are the space coordinates, then t:
// (x), (x, y), (x, y, z), (x, t), (x, y, t), (x, y, z, t).
//
// Faces are named x_min, x_max, y_min, … ; "boundary" means all space faces, "initial" the
// slice t = t0. Sampling draws from the caller's random engine only, so a run's points are
// reproducible from its seed (and its saved engine state on resume). When the engine carries
// a low-discrepancy sequence (solvers/sampling/random.h), the unit-cube points come from it: the
// interior uses input_dim coordinates, the initial slice the space ones, a union of faces
// one more coordinate to pick the face (so each face gets a share ∝ its measure).
//
// A domain may instead hold a geometry (solvers/geometry/geometry.h: shapes, holes, meshes):
// lower/upper are then its bounding box, interior points are uniform over the shape (and time
// uniform, from a one-dimensional stream of its own when a sequence is attached), the boundary
// is sampled by named part with normals (sample_boundary), and the box's faces do not exist
// (face, sample_face and sample_faces throw std::logic_error), so that code written for boxes
// cannot silently sample the bounding box's faces. In a config it is `domain.geometry`
// (solvers/geometry/geometry_config.h), read by from_config with the config's folder; the
// conditions then name parts (condition_list.h), the hard ansatz takes φ from
// Geometry::distance (ansatz.h), and the grid outputs mask the points outside.
//
// Parameters (a parametric field, issue 28): a constant declared as a range (`constants:
// {nu: {range: [0.005, 0.05]}}`, solvers/problems/pde.cc) becomes one more input column,
// after the coordinates: (x, t, nu). The domain is the one place that knows these columns:
// input_dim() counts them, input_names() names them (so expressions read `nu` as the
// column), and every sampler (interior, faces, initial slice, geometry boundary) draws each
// point's parameters from their ranges, uniform or log-uniform. Derivative streams differentiate
// along the tangents a term asks for, so a parameter column is a passive input unless an
// expression differentiates by it: u_x, u_xx, lap(u) have zero tangent entries there. Faces,
// normals, the initial slice and the grid outputs concern the coordinates only; a grid is
// evaluated at one given value of the parameters (GridMetrics per held-out value, run.cc).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/config.h"
#include "io/expression.h"
#include "solvers/sampling/random.h"

namespace nfield::solvers {
namespace geometry {
class Geometry;
struct Selection;
struct Measure;
}  // namespace geometry

// A parameter column: its name, range and how points draw it.
struct DomainParameter {
  std::string name;
  double lower = 0, upper = 1;  // lower < upper; lower > 0 for log
  bool log = false;             // log-uniform (each decade the same share) rather than uniform
  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
  // The value at u ∈ [0, 1] of the unit interval.
  double at(double u) const;
  // The middle of the range (geometric for log): the value a grid is evaluated at by default.
  double middle() const { return at(0.5); }
};

struct Face {
  int axis = 0;        // space axis
  bool upper = false;  // x_max rather than x_min
  std::string name() const;
};

class Domain {
 public:
  Domain(std::vector<double> lower, std::vector<double> upper,
         std::optional<std::pair<double, double>> time = std::nullopt);
  // A domain shaped by `geometry` (2-D or 3-D), optionally times [t0, t1].
  explicit Domain(std::shared_ptr<const geometry::Geometry> geometry,
                  std::optional<std::pair<double, double>> time = std::nullopt);
  // Reads `domain:` {lower, upper, time}; errors name the file, line and key. A `geometry`
  // key is refused (the problem takes boxes only).
  static Domain from_config(const io::ConfigNode& node);
  // Reads `domain:` {lower, upper, time} or {geometry, time}; files of the geometry (meshes,
  // polygons) are relative to config_dir.
  static Domain from_config(const io::ConfigNode& node, const std::filesystem::path& config_dir);
  // The `domain:` of a problem over a 3-D box without time (sdf, occupancy): [−1, 1]³ when
  // `root` has none; errors say that `what` (e.g. "a signed distance field") needs it so.
  static Domain box_3d_from_config(const io::ConfigNode& root, const std::string& what);

  int space_dim() const { return static_cast<int>(lower_.size()); }
  bool has_time() const { return time_.has_value(); }
  // The coordinates (space, then t), then the parameters: a field's input columns.
  int coordinate_dim() const { return space_dim() + (has_time() ? 1 : 0); }
  int input_dim() const { return coordinate_dim() + parameter_count(); }
  // Adds a parameter column after the coordinates and those added before (the name must be
  // new: not x, y, z, t or another parameter's). Throws std::invalid_argument.
  void add_parameter(DomainParameter parameter);
  const std::vector<DomainParameter>& parameters() const { return parameters_; }
  int parameter_count() const { return static_cast<int>(parameters_.size()); }
  int parameter_column(int k) const { return coordinate_dim() + k; }
  // The parameter's index, -1 when `name` is none.
  int parameter_index(const std::string& name) const;
  // The middle value of each parameter (DomainParameter::middle).
  Eigen::VectorXd parameter_middles() const;
  int time_column() const { return space_dim(); }
  const std::vector<double>& lower() const { return lower_; }
  const std::vector<double>& upper() const { return upper_; }
  std::pair<double, double> time() const { return time_.value_or(std::pair{0.0, 0.0}); }
  // Input lower/upper including time and the parameters' ranges.
  Eigen::VectorXd input_lower() const;
  Eigen::VectorXd input_upper() const;

  // Expression variable order for io::Expression so that a point row (inputs) maps onto
  // x, y, z, t by name: e.g. {"x", "t", "y", "z"} for 1D + time.
  std::vector<std::string> expression_variables() const;
  std::vector<std::string> input_names() const;

  std::vector<Face> faces() const;
  // Parses "x_min", …, case-insensitive; the error lists the valid names.
  Face face(const std::string& name) const;

  Eigen::MatrixXd sample_interior(Random& rng, Eigen::Index n) const;
  // n interior points where `where` (an expression over expression_variables()) is nonzero:
  // sample_interior's points, those outside the region dropped, so uniform over the region
  // (a sequence's points restricted to it). Throws std::runtime_error when 10⁶ candidates in
  // a row miss the region.
  Eigen::MatrixXd sample_interior_where(Random& rng, Eigen::Index n, const io::Expression& where) const;
  // On one face (time uniform in [t0, t1] when present).
  Eigen::MatrixXd sample_face(const Face& face, Random& rng, Eigen::Index n) const;
  // On the union of `faces`, each chosen with probability ∝ its measure.
  Eigen::MatrixXd sample_faces(const std::vector<Face>& faces, Random& rng, Eigen::Index n) const;
  // At t = t0, space uniform.
  Eigen::MatrixXd sample_initial(Random& rng, Eigen::Index n) const;

  // Outward unit normal of a face (space components only, input_dim long, zero in t).
  Eigen::VectorXd normal(const Face& face) const;

  // ---- with a geometry ----------------------------------------------------------------
  const geometry::Geometry* geometry() const { return geometry_.get(); }
  // Points on the selected parts (time uniform when present), n × input_dim, with their
  // outward unit normals (n × input_dim, 0 in t) and part ids. Throws std::logic_error
  // without a geometry.
  struct BoundaryPoints {
    Eigen::MatrixXd points, normals;
    Eigen::VectorXi parts;
  };
  BoundaryPoints sample_boundary(const geometry::Selection& selection, Random& rng, Eigen::Index n) const;
  // The space measure: the box's volume (exact), or the geometry's (exact or estimated).
  geometry::Measure space_measure() const;
  // Per row of `points` (n × space_dim or input_dim): inside the domain (always, for a box).
  Eigen::Array<bool, Eigen::Dynamic, 1> contains_rows(const Eigen::MatrixXd& points) const;
  // Outward unit normals (n × input_dim, 0 in t) at boundary points of the geometry.
  Eigen::MatrixXd boundary_normals(const Eigen::MatrixXd& points) const;

 private:
  double face_measure(const Face& face) const;
  void require_box(const char* what) const;
  // Draws the parameter columns of x from their ranges (unit points of the engine's own).
  void draw_parameters(Random& rng, Eigen::MatrixXd& x) const;
  // Maps unit-interval columns of x onto the parameters' ranges.
  void map_parameters(Eigen::MatrixXd& x) const;
  std::vector<double> lower_, upper_;
  std::vector<DomainParameter> parameters_;
  std::shared_ptr<const geometry::Geometry> geometry_;
  std::optional<std::pair<double, double>> time_;
};

// A region of the interior for more residual points (poisson's `focus`, pde's `where`):
// node[key], an expression over domain.expression_variables() and `constants`, nonzero in the
// region. A ConfigError at the key when no point of 2¹⁴ drawn in the domain lies in it.
std::shared_ptr<const io::Expression> read_interior_region(const io::ConfigNode& node, std::string_view key,
                                                           const Domain& domain,
                                                           io::ExpressionConstants constants = {});

}  // namespace nfield::solvers
