// SPDX-License-Identifier: MIT
#include "solvers/problems/wave_reference.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace nfield::solvers {
namespace {

std::invalid_argument bad(const std::string& what) {
  return std::invalid_argument("wave reference: " + what);
}

// Catmull–Rom weights of the nodes j−1, j, j+1, j+2 at the fraction s ∈ [0, 1] past node j.
std::array<double, 4> catmull_rom(double s) {
  const double s2 = s * s, s3 = s2 * s;
  return {0.5 * (-s3 + 2 * s2 - s), 0.5 * (3 * s3 - 5 * s2 + 2), 0.5 * (-3 * s3 + 4 * s2 + s),
          0.5 * (s3 - s2)};
}

}  // namespace

// The leapfrog's state: the node coordinates (x…, t), which nodes a Dirichlet face holds, the
// Neumann ghost terms, and the coefficients and boundary values at the time last evaluated.
struct WaveReference::Stepper {
  // A free node on a Neumann face: its Laplacian gets the term 2g/h_a.
  struct Ghost {
    Eigen::Index node;
    int axis, face;
  };
  // Per face, once: the entries it sets (of the Dirichlet values, or of the ghost terms of a
  // Neumann face) and their points.
  struct FaceNodes {
    std::vector<Eigen::Index> rows;
    Eigen::MatrixXd points;
  };

  Stepper(const WaveReference& grid, const Domain& domain, const WaveReferenceData& data, Eigen::Index nodes);

  void at_time(Eigen::MatrixXd& p, double t) const { p.col(grid.dim_).setConstant(t); }
  void evaluate_coefficients(double t);
  void evaluate_boundary(double t);
  // Coefficients and boundary values at t, where they depend on t.
  void advance_to(double t) {
    if (speed_varies || source_varies) evaluate_coefficients(t);
    if (boundary_varies) evaluate_boundary(t);
  }
  // acc = c²Δ_h u + f at the free nodes (Dirichlet nodes: 0).
  void acceleration(const Eigen::VectorXd& u, Eigen::VectorXd& acc) const;
  void set_dirichlet(Eigen::VectorXd& u) const {
    for (std::size_t k = 0; k < dirichlet_nodes.size(); ++k) u(dirichlet_nodes[k]) = dirichlet(k);
  }

  const WaveReference& grid;
  const WaveReferenceData& data;
  const Eigen::Index nodes;
  Eigen::MatrixXd points;
  Eigen::Array<bool, Eigen::Dynamic, 1> fixed;  // held by a Dirichlet face
  std::vector<Eigen::Index> dirichlet_nodes;
  std::vector<Ghost> ghosts;
  std::vector<FaceNodes> face_nodes;
  std::array<double, 3> inv_h2{0, 0, 0};
  bool speed_varies, source_varies, boundary_varies;
  Eigen::VectorXd c2, source, dirichlet, ghost_term;

 private:
  void place_nodes();
  std::vector<int> dirichlet_faces(const Domain& domain, const Eigen::MatrixXd& dirichlet_points) const;
  void find_ghosts();
  void group_by_face(const Eigen::MatrixXd& dirichlet_points, const std::vector<int>& dirichlet_face);
};

WaveReference::Stepper::Stepper(const WaveReference& grid, const Domain& domain, const WaveReferenceData& data,
                                Eigen::Index nodes)
    : grid(grid), data(data), nodes(nodes) {
  place_nodes();
  Eigen::MatrixXd dirichlet_points(static_cast<Eigen::Index>(dirichlet_nodes.size()), grid.dim_ + 1);
  for (std::size_t k = 0; k < dirichlet_nodes.size(); ++k) dirichlet_points.row(k) = points.row(dirichlet_nodes[k]);
  const std::vector<int> dirichlet_face = dirichlet_faces(domain, dirichlet_points);
  find_ghosts();
  group_by_face(dirichlet_points, dirichlet_face);
  for (int a = 0; a < grid.dim_; ++a) inv_h2[a] = 1.0 / (grid.h_[a] * grid.h_[a]);
  speed_varies = data.speed.uses("t");
  source_varies = data.source.uses("t");
  boundary_varies =
      std::any_of(data.faces.begin(), data.faces.end(), [](const auto& f) { return f->value.uses("t"); });
}

// Node coordinates (x…, t0) for the expressions, and which nodes a Dirichlet face holds.
void WaveReference::Stepper::place_nodes() {
  const int dim = grid.dim_;
  points.resize(nodes, dim + 1);
  fixed = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(nodes, false);
  std::array<int, 3> i{0, 0, 0};
  for (Eigen::Index n = 0; n < nodes; ++n) {
    for (int a = 0; a < dim; ++a) {
      i[a] = static_cast<int>((n / grid.stride_[a]) % (grid.cells_[a] + 1));
      points(n, a) = grid.lower_[a] + i[a] * grid.h_[a];
      for (int side = 0; side < 2; ++side)
        if (i[a] == (side ? grid.cells_[a] : 0) && data.faces[2 * a + side]->dirichlet) fixed(n) = true;
    }
  }
  points.col(dim).setConstant(grid.t0_);
  for (Eigen::Index n = 0; n < nodes; ++n)
    if (fixed(n)) dirichlet_nodes.push_back(n);
}

// Which Dirichlet expression each Dirichlet node takes (the first face that holds it).
std::vector<int> WaveReference::Stepper::dirichlet_faces(const Domain& domain,
                                                         const Eigen::MatrixXd& dirichlet_points) const {
  std::vector<int> dirichlet_face(dirichlet_nodes.size(), -1);
  for (std::size_t k = 0; k < dirichlet_nodes.size(); ++k)
    for (int a = 0; a < grid.dim_ && dirichlet_face[k] < 0; ++a)
      for (int side = 0; side < 2 && dirichlet_face[k] < 0; ++side) {
        const double coordinate = side ? domain.upper()[a] : domain.lower()[a];
        if (std::abs(dirichlet_points(k, a) - coordinate) <= 1e-12 * std::max(1.0, std::abs(coordinate)) &&
            data.faces[2 * a + side]->dirichlet)
          dirichlet_face[k] = 2 * a + side;
      }
  return dirichlet_face;
}

// Neumann ghost terms: per (face, free node on it) the term 2g/h_a of the Laplacian.
void WaveReference::Stepper::find_ghosts() {
  for (Eigen::Index n = 0; n < nodes; ++n) {
    if (fixed(n)) continue;
    for (int a = 0; a < grid.dim_; ++a) {
      const int ia = static_cast<int>((n / grid.stride_[a]) % (grid.cells_[a] + 1));
      if (ia == 0) ghosts.push_back({n, a, 2 * a});
      if (ia == grid.cells_[a]) ghosts.push_back({n, a, 2 * a + 1});
    }
  }
}

void WaveReference::Stepper::group_by_face(const Eigen::MatrixXd& dirichlet_points,
                                           const std::vector<int>& dirichlet_face) {
  const int dim = grid.dim_;
  Eigen::MatrixXd ghost_points(static_cast<Eigen::Index>(ghosts.size()), dim + 1);
  for (std::size_t k = 0; k < ghosts.size(); ++k) ghost_points.row(k) = points.row(ghosts[k].node);
  face_nodes.resize(2 * dim);
  for (int f = 0; f < 2 * dim; ++f) {
    FaceNodes& nodes_of_face = face_nodes[f];
    const bool dirichlet_face_kind = data.faces[f]->dirichlet;
    const Eigen::MatrixXd& all = dirichlet_face_kind ? dirichlet_points : ghost_points;
    const std::size_t count = dirichlet_face_kind ? dirichlet_nodes.size() : ghosts.size();
    for (std::size_t k = 0; k < count; ++k)
      if ((dirichlet_face_kind ? dirichlet_face[k] : ghosts[k].face) == f)
        nodes_of_face.rows.push_back(static_cast<Eigen::Index>(k));
    nodes_of_face.points.resize(static_cast<Eigen::Index>(nodes_of_face.rows.size()), dim + 1);
    for (std::size_t r = 0; r < nodes_of_face.rows.size(); ++r)
      nodes_of_face.points.row(r) = all.row(nodes_of_face.rows[r]);
  }
}

// The Dirichlet values and the Neumann ghost terms at t.
void WaveReference::Stepper::evaluate_boundary(double t) {
  dirichlet.setZero(static_cast<Eigen::Index>(dirichlet_nodes.size()));
  ghost_term.setZero(static_cast<Eigen::Index>(ghosts.size()));
  for (int f = 0; f < 2 * grid.dim_; ++f) {
    FaceNodes& nodes_of_face = face_nodes[f];
    at_time(nodes_of_face.points, t);
    const Eigen::VectorXd g = data.faces[f]->value.evaluate(nodes_of_face.points);
    for (std::size_t r = 0; r < nodes_of_face.rows.size(); ++r) {
      const Eigen::Index row = nodes_of_face.rows[r];
      if (data.faces[f]->dirichlet)
        dirichlet(row) = g(r);
      else
        ghost_term(row) = 2.0 * g(r) / grid.h_[ghosts[row].axis];
    }
  }
}

// The speed squared and the source at the nodes at t (no source vector when it is 0).
void WaveReference::Stepper::evaluate_coefficients(double t) {
  at_time(points, t);
  const Eigen::VectorXd c = data.speed.evaluate(points);
  for (Eigen::Index n = 0; n < nodes; ++n)
    if (!(std::isfinite(c(n)) && c(n) > 0))
      throw std::runtime_error("wave reference: the speed is " + std::to_string(c(n)) + " at node " +
                               std::to_string(n) + " (t = " + std::to_string(t) + "); expected c > 0");
  c2 = c.array().square().matrix();
  source = data.source.is_constant() && data.source.evaluate(std::span<const double>()) == 0
               ? Eigen::VectorXd()
               : data.source.evaluate(points);
}

void WaveReference::Stepper::acceleration(const Eigen::VectorXd& u, Eigen::VectorXd& acc) const {
  const int dim = grid.dim_;
  const std::array<int, 3>& cells = grid.cells_;
  const std::array<Eigen::Index, 3>& stride = grid.stride_;
  const int last[3] = {cells[0], dim > 1 ? cells[1] : 0, dim > 2 ? cells[2] : 0};
  acc.setZero(nodes);
  const double* v = u.data();
  for (int i2 = 0; i2 <= last[2]; ++i2)
    for (int i1 = 0; i1 <= last[1]; ++i1) {
      const Eigen::Index row = stride[1] * i1 + stride[2] * i2;
      const int ib[3] = {0, i1, i2};
      for (int i0 = 0; i0 <= last[0]; ++i0) {
        const Eigen::Index n = row + i0;
        if (fixed(n)) continue;
        double lap = 0;
        for (int a = 0; a < dim; ++a) {
          const Eigen::Index s = stride[a];
          const int ia = a == 0 ? i0 : ib[a];
          // At a Neumann face the ghost's mirror part: the missing neighbour is the other one.
          const double minus = ia > 0 ? v[n - s] : v[n + s];
          const double plus = ia < cells[a] ? v[n + s] : v[n - s];
          lap += (minus - 2 * v[n] + plus) * inv_h2[a];
        }
        acc(n) = c2(n) * lap;
      }
    }
  for (std::size_t k = 0; k < ghosts.size(); ++k) acc(ghosts[k].node) += c2(ghosts[k].node) * ghost_term(k);
  if (source.size() > 0) acc += source;
  for (const Eigen::Index n : dirichlet_nodes) acc(n) = 0;
}

WaveReference::WaveReference(const Domain& domain, const WaveReferenceData& data,
                             const WaveReferenceOptions& options,
                             std::function<void(long, long)> progress) {
  const Eigen::Index nodes = set_up_grid(domain, data, options);
  Stepper stepper(*this, domain, data, nodes);
  const long steps_per_snapshot = choose_time_step(stepper, options);
  march(stepper, steps_per_snapshot, progress);
}

Eigen::Index WaveReference::set_up_grid(const Domain& domain, const WaveReferenceData& data,
                                        const WaveReferenceOptions& options) {
  if (!domain.has_time()) throw bad("the domain has no time interval");
  dim_ = domain.space_dim();
  if (dim_ < 1 || dim_ > 3) throw bad("1 to 3 space dimensions");
  if (static_cast<int>(data.faces.size()) != 2 * dim_) throw bad("one condition per face expected");
  for (const Face& face : domain.faces())
    if (!data.faces[2 * face.axis + (face.upper ? 1 : 0)])
      throw bad("face " + face.name() + " has no boundary condition (every face needs a dirichlet or neumann item)");
  const int cells = options.cells > 0 ? options.cells : (dim_ == 1 ? 4096 : dim_ == 2 ? 512 : 96);
  if (cells < 4 || cells > (1 << 20)) throw bad("cells = " + std::to_string(cells) + ": expected 4 to 2^20");
  if (!(options.cfl > 0 && options.cfl <= 1))
    throw bad("cfl = " + std::to_string(options.cfl) + ": expected 0 < cfl <= 1 (the scheme's stability limit)");
  if (options.snapshots < 2) throw bad("snapshots = " + std::to_string(options.snapshots) + ": expected at least 2");

  double longest = 0;
  for (int a = 0; a < dim_; ++a) longest = std::max(longest, domain.upper()[a] - domain.lower()[a]);
  Eigen::Index nodes = 1;
  for (int a = 0; a < dim_; ++a) {
    const double length = domain.upper()[a] - domain.lower()[a];
    cells_[a] = std::max(4, static_cast<int>(std::lround(cells * length / longest)));
    h_[a] = length / cells_[a];
    lower_[a] = domain.lower()[a];
    stride_[a] = nodes;
    nodes *= cells_[a] + 1;
  }
  for (int a = dim_; a < 3; ++a) stride_[a] = nodes;
  const double bytes = 8.0 * static_cast<double>(nodes) * options.snapshots;
  if (bytes > 4.0 * (1ull << 30))
    throw bad("cells = " + std::to_string(cells) + " and snapshots = " + std::to_string(options.snapshots) +
              " need " + std::to_string(bytes / (1ull << 30)).substr(0, 5) + " GiB; the limit is 4 GiB");
  std::tie(t0_, t1_) = domain.time();
  return nodes;
}

// Δt: `cfl` of the stability limit at the largest speed (over the nodes at t0, and at 11 times
// if it varies in time), shortened to a whole number of steps per snapshot spacing.
long WaveReference::choose_time_step(Stepper& stepper, const WaveReferenceOptions& options) {
  double c2_max = 0;
  for (int k = 0; k <= (stepper.speed_varies ? 10 : 0); ++k) {
    stepper.evaluate_coefficients(t0_ + (t1_ - t0_) * k / 10.0);
    c2_max = std::max(c2_max, stepper.c2.maxCoeff());
  }
  double inverse_h2 = 0;
  for (int a = 0; a < dim_; ++a) inverse_h2 += 1.0 / (h_[a] * h_[a]);
  const double dt_limit = options.cfl / std::sqrt(c2_max * inverse_h2);
  snapshot_spacing_ = (t1_ - t0_) / (options.snapshots - 1);
  const long steps_per_snapshot = std::max(1L, static_cast<long>(std::ceil(snapshot_spacing_ / dt_limit)));
  dt_ = snapshot_spacing_ / steps_per_snapshot;
  steps_ = steps_per_snapshot * (options.snapshots - 1);
  return steps_per_snapshot;
}

// The leapfrog from t0 to t1, keeping u and u_t every `steps_per_snapshot` steps.
void WaveReference::march(Stepper& stepper, long steps_per_snapshot,
                          const std::function<void(long, long)>& progress) {
  stepper.evaluate_coefficients(t0_);
  stepper.evaluate_boundary(t0_);
  stepper.at_time(stepper.points, t0_);
  Eigen::VectorXd previous = stepper.data.initial_value.evaluate(stepper.points);
  const Eigen::VectorXd velocity = stepper.data.initial_velocity.evaluate(stepper.points);
  stepper.set_dirichlet(previous);
  u_.push_back(previous.cast<float>());
  u_t_.push_back(velocity.cast<float>());
  Eigen::VectorXd acc, current, next;
  stepper.acceleration(previous, acc);
  current = previous + dt_ * velocity + 0.5 * dt_ * dt_ * acc;
  stepper.advance_to(t0_ + dt_);
  stepper.set_dirichlet(current);

  const auto started = std::chrono::steady_clock::now();
  auto last_report = started;
  for (long n = 1; n <= steps_; ++n) {  // current is uⁿ, previous uⁿ⁻¹
    const double t = t0_ + n * dt_;
    stepper.acceleration(current, acc);
    next = 2 * current - previous + dt_ * dt_ * acc;
    stepper.advance_to(t + dt_);
    stepper.set_dirichlet(next);
    if (!next.allFinite())
      throw std::runtime_error("wave reference: the solution is not finite at t = " + std::to_string(t + dt_));
    if (n % steps_per_snapshot == 0) {
      u_.push_back(current.cast<float>());
      u_t_.push_back(((next - previous) / (2 * dt_)).cast<float>());
    }
    previous.swap(current);
    current.swap(next);
    const auto now = std::chrono::steady_clock::now();
    if (progress && now - last_report > std::chrono::seconds(2)) {
      progress(n, steps_);
      last_report = now;
    }
  }
}

double WaveReference::interpolate_space(const Eigen::VectorXf& snapshot, const Eigen::RowVectorXd& x) const {
  // Per axis: four consecutive nodes from first[a] and their weights. A stencil node beyond
  // a face is the quadratic extrapolation 3u₀ − 3u₁ + u₂ of the nearest three, which keeps
  // the third order there (clamping would drop it to the first).
  std::array<int, 3> first{0, 0, 0};
  std::array<std::array<double, 4>, 3> weight{};
  for (int a = 0; a < 3; ++a) weight[a] = {1, 0, 0, 0};
  for (int a = 0; a < dim_; ++a) {
    const int last = cells_[a];
    const double s = std::clamp((x(a) - lower_[a]) / h_[a], 0.0, static_cast<double>(last));
    const int base = std::min(static_cast<int>(s), last - 1);
    const std::array<double, 4> w = catmull_rom(s - base);
    first[a] = std::clamp(base - 1, 0, last - 3);
    weight[a] = {0, 0, 0, 0};
    const auto add = [&](int node, double value) { weight[a][node - first[a]] += value; };
    for (int q = 0; q < 4; ++q) {
      const int m = base - 1 + q;
      if (m < 0) {
        add(0, 3 * w[q]), add(1, -3 * w[q]), add(2, w[q]);
      } else if (m > last) {
        add(last, 3 * w[q]), add(last - 1, -3 * w[q]), add(last - 2, w[q]);
      } else {
        add(m, w[q]);
      }
    }
  }
  double sum = 0;
  const int span[3] = {4, dim_ > 1 ? 4 : 1, dim_ > 2 ? 4 : 1};
  for (int c = 0; c < span[2]; ++c)
    for (int b = 0; b < span[1]; ++b)
      for (int a = 0; a < span[0]; ++a) {
        const double w = weight[0][a] * weight[1][b] * weight[2][c];
        if (w != 0) sum += w * snapshot(node({first[0] + a, first[1] + b, first[2] + c}));
      }
  return sum;
}

Eigen::VectorXd WaveReference::values(const Eigen::MatrixXd& x) const {
  if (x.cols() != dim_ + 1) throw std::invalid_argument("WaveReference::values: expected " + std::to_string(dim_ + 1) + " columns");
  Eigen::VectorXd out(x.rows());
  const int last = static_cast<int>(u_.size()) - 1;
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const double s = std::clamp((x(r, dim_) - t0_) / snapshot_spacing_, 0.0, static_cast<double>(last));
    const int k = std::min(static_cast<int>(s), last - 1);
    const double f = s - k;
    const Eigen::RowVectorXd p = x.row(r);
    const double u0 = interpolate_space(u_[k], p), u1 = interpolate_space(u_[k + 1], p);
    if (f == 0) {
      out(r) = u0;
      continue;
    }
    const double v0 = interpolate_space(u_t_[k], p) * snapshot_spacing_;
    const double v1 = interpolate_space(u_t_[k + 1], p) * snapshot_spacing_;
    // Cubic Hermite on [k, k + 1].
    const double f2 = f * f, f3 = f2 * f;
    out(r) = (2 * f3 - 3 * f2 + 1) * u0 + (f3 - 2 * f2 + f) * v0 + (-2 * f3 + 3 * f2) * u1 + (f3 - f2) * v1;
  }
  return out;
}

}  // namespace nfield::solvers
