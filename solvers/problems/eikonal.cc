// SPDX-License-Identifier: MIT
//
// Eikonal: first-arrival travel times u from a point source x₀ in a medium of speed v(x),
//
//   |∇u| = 1/v(x),   u(x₀) = 0,
//
// in a box of 2 or 3 space dimensions (no time axis).
//
//   problem: eikonal
//   equation:
//     source: [0.5, 0.25]           # x₀, inside the domain
//     speed: "1"                    # v(x) > 0, an expression; or instead a two-layer medium:
//     layers: {axis: y, interface: 0.5, speeds: [1, 2]}   # v = 1 for y < 0.5, 2 for y ≥ 0.5
//     factored: false               # u = T₀·(1 + τ), the network gives τ (below)
//     exact: "..."                  # optional, for a non-constant `speed` expression
//     weight: 1                     # weight of the "pde" loss term
//     source_fraction: 0.25         # of the "pde" points, drawn around the source (below)
//     outflow_weight: 1             # weight of the "outflow" loss term (0: none)
//     source_weight: 10             # weight of the "source" loss term (0: none)
//     interface_weight: 0           # weight of the "interface" loss term (layers; 0: none)
//     viscosity: 0                  # ε of the vanishing-viscosity term (below), or a list
//                                   # with one ε per training stage
//     viscosity_form: laplacian     # or concave (below); or a list, one per training stage
//
// Loss terms:
//   "pde"     (batch `interior`) r = |∇u| − 1/v(x). The residual is not linear in the output
//             streams: its residual (eikonal_residual.cc) reads the value and gradient
//             tangent streams; its adjoint comes from Jets (∂|g|/∂g = g/|g|, taken as 0
//             where |g| = 0). A fraction `source_fraction` of its points is drawn with
//             |x − x₀| uniform in [0, R] (R the distance to the farthest corner; density
//             ∝ 1/r^{d−1}), the rest uniformly, so
//             that the neighbourhood of the source, whose small area uniform points hardly
//             see, pins the solution there.
//   "outflow" (batch `boundary`, on all faces) r = [min(0, ∇u·n), min(0, u)/L], n the outward
//             normal, L the domain's diagonal: every first-arrival ray starts at the source,
//             so no wave enters the box (∂u/∂n ≥ 0) and times are ≥ 0. |∇u| = 1/v alone also
//             holds for fields with extra "sources" outside or on the box (u decreasing towards
//             a face, e.g. the mirror branch −u in a region), which a network finds readily
//             (the two-layer example's figures with and without the term: docs/experiments.md).
//   "source"  (batch `source`) the source condition at x₀ itself; its n points are all x₀,
//             so `source: 1` is enough. r = u(x₀) (plain), r = τ(x₀) (factored).
//   "interface" (batch `interface`, only with `layers` and interface_weight > 0) points on
//             the interface plane, 1e-6 of the box off it on the source's side, so that cusp
//             features (fields/encodings.h) give that side's one-sided derivatives. With n
//             the normal pointing away from the source's layer, ∇_t u = ∇u − (∇u·n) n:
//               r = max(0, −∇u·n) (1/v_far − |∇_t u|).
//             Where the first arrival crosses the interface, ∇u·n > 0 and r = 0. Where it
//             leaves the interface back into the source's layer (∇u·n < 0) it is a head wave,
//             which travelled along the interface at the far layer's speed: |∇_t u| = 1/v_far.
//             (A source in the faster layer has no head wave; there r > 0 wherever ∇u·n < 0.)
//             A network with cusp features makes the kink on the plane at no cost, including
//             a V-shaped one that emits waves into the source's layer earlier than the far
//             layer could carry them along the interface (|∇_t u| < 1/v_far); the Laplacian of
//             the viscous term does not see a kink that is exactly on the plane; this term
//             does (figures: docs/experiments.md).
//
// Vanishing viscosity (`viscosity: ε`): the "pde" residual becomes r = |∇u| − 1/v − ε Δu.
// |∇u| = 1/v at the collocation points also holds for fields with kinks of the wrong kind:
// ridges across which u is convex, lines that "emit" waves earlier than the first arrival,
// which a network rounds off between the points at little cost, and which Adam and LM did
// find on the two-layer example (docs/experiments.md). The first
// arrival is the limit ε → 0 of the viscous equation (the viscosity solution of Crandall and
// Lions): rounding a concave kink (two fronts meeting) gives Δu < 0 together with |∇u| < 1/v,
// which the term balances, while rounding a convex one gives Δu > 0 and a residual that grows.
// ε biases the result by about ε times the curvature, so it is meant to fall over the training
// stages to a small value: a list gives one ε per stage (falling to 0 let LM drift back to
// such fields; held at a small ε it did not). Factored, the
// term is ε (Δu − (1 + τ) ΔT₀) = ε (2 ∇T₀·∇τ + T₀ Δτ): the curvature ΔT₀ = (d − 1)/(v₀ |x − x₀|)
// of the analytic factor is left out, as it would dominate the residual near the source,
// where there is no branch to select.
//
// `viscosity_form: concave` keeps only the negative part: r = |∇u| − 1/v − ε min(0, Δu), with
// the whole Δu = (1 + τ) ΔT₀ + 2 ∇T₀·∇τ + T₀ Δτ when factored. The term ε Δu biases smooth
// regions by ε times the curvature and, where a rounded kink is crossed, by ε times the jump
// of the normal derivative, everywhere beyond it. Fronts spreading from a point source have
// Δu > 0 (the cone's ΔT₀ among them, which therefore needs no special case) as long as no
// focusing occurs, and fronts that meet have Δu < 0; the concave form keeps the part that
// makes meeting fronts cheap to round and drops the bias of the spreading ones. It no longer
// makes ridges dear (they go unpenalized, as without viscosity). The operator stays
// degenerate elliptic (nonincreasing in D²u), so ε → 0 still gives the viscosity solution.
// With cusp features and the "interface" term it ended lower than the full Laplacian, so
// configs/accuracy_eikonal_layered.yaml uses it (seed tables: docs/experiments.md).
//
// The solution is a cone at x₀ (u ≈ |x − x₀|/v₀), whose kink a smooth network rounds off.
// With `factored: true` the travel time is factored as u = T₀ (1 + τ) with the analytic
// T₀ = |x − x₀|/v₀ (v₀ = v(x₀)) (Fomel et al. 2009, Treister & Haber 2016; PINNeik, bin Waheed
// et al. 2021), and the network represents the smooth relative correction τ (0 at the source,
// τ ≡ 0 in a constant medium). The residual forms u and ∇u = (1 + τ) ∇T₀ + T₀ ∇τ from the
// network's value and gradient streams and sends its adjoints back to them:
// τ̄ = ḡ·∇T₀, ∇τ̄ = T₀ ḡ with ḡ = r̄ ∇u/|∇u|. The source condition becomes τ(x₀) = 0 (the
// equation at x₀ reads (1 + τ(x₀))/v₀ = 1/v(x₀)). The offset 1 helps: |∇u| = 1/v is also
// solved by −u, and a network that starts near u ≈ 0 (τ ≈ −1) picks either sign region by
// region; starting near τ = 0 (u ≈ T₀) it starts on the right branch, where the plain form
// did not converge at all in the same budget (docs/experiments.md).
//
// Metrics: without factoring, the grid's rel_l2 and max_abs_err (solution.vti: u, exact_u,
// error_u) are those of the travel time. With factoring the network output is τ
// (solution.vti: "tau"), has_exact() is false so that the grid does not compare τ, whose
// exact value T/T₀ − 1 vanishes in a constant medium, and write_outputs writes rel_l2 and
// max_abs_err of the travel time u = T₀ (1 + τ) instead, and travel_time.vti with
// travel_time, exact_travel_time, error_travel_time and exact_tau; reported_error gives the
// same rel_l2 after every training stage (metrics.json `stages`).
//
// Exact solutions (error metrics):
//   constant speed   u = |x − x₀|/v.
//   two layers       the first arrival over three kinds of ray, v_s the speed of the
//                    source's layer, v_o the other one, h_s and h_r the distances of source
//                    and receiver from the interface plane, Δ their distance along it:
//                    - receiver in the source's layer: the direct ray |x − x₀|/v_s, and if
//                      v_o > v_s the head wave Δ/v_o + (h_s + h_r) √(1/v_s² − 1/v_o²), which
//                      exists from the critical distance Δ ≥ (h_s + h_r) tan θ_c on
//                      (sin θ_c = v_s/v_o);
//                    - receiver in the other layer: the refracted ray through the interface
//                      point at distance s from the source's foot point, minimizing
//                      √(s² + h_s²)/v_s + √((Δ − s)² + h_r²)/v_r over s ∈ [0, Δ] (Fermat;
//                      convex in s, solved by bisection on its derivative — Snell's law).
//   other `speed`    the `exact` expression if given, else none.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>

#include "io/grid.h"
#include "io/vtk_image.h"
#include "solvers/problems/eikonal_residual.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

// A two-layer medium: speeds[0] where x[axis] < interface, speeds[1] elsewhere.
struct Layers {
  int axis = 1;
  double interface = 0;
  double speeds[2] = {1, 1};

  int layer(const double* x) const { return x[axis] < interface ? 0 : 1; }
  double speed(const double* x) const { return speeds[layer(x)]; }
};

// The first-arrival time from x0 to x (both `d` long) in a two-layer medium; see the header
// comment for the three kinds of ray.
double layered_travel_time(const Layers& m, const double* x0, const double* x, int d) {
  const int ls = m.layer(x0), lr = m.layer(x);
  const double hs = std::abs(x0[m.axis] - m.interface), hr = std::abs(x[m.axis] - m.interface);
  double delta2 = 0, dist2 = 0;
  for (int a = 0; a < d; ++a) {
    const double e = x[a] - x0[a];
    dist2 += e * e;
    if (a != m.axis) delta2 += e * e;
  }
  const double delta = std::sqrt(delta2);
  const double vs = m.speeds[ls], vo = m.speeds[1 - ls];
  if (ls == lr) {
    double t = std::sqrt(dist2) / vs;
    if (vo > vs) {
      const double critical = (hs + hr) * vs / std::sqrt(vo * vo - vs * vs);
      if (delta >= critical)
        t = std::min(t, delta / vo + (hs + hr) * std::sqrt(1 / (vs * vs) - 1 / (vo * vo)));
    }
    return t;
  }
  // Refracted ray: f(s) = √(s² + hs²)/vs + √((Δ − s)² + hr²)/vr is convex on [0, Δ]; its
  // derivative is increasing, ≤ 0 at 0 and ≥ 0 at Δ. Bisection to the last bit.
  const double vr = m.speeds[lr];
  auto slope = [&](double s) {
    const double a = std::hypot(s, hs), b = std::hypot(delta - s, hr);
    return (a > 0 ? s / (vs * a) : 0.0) - (b > 0 ? (delta - s) / (vr * b) : 0.0);
  };
  double lo = 0, hi = delta;
  for (int iteration = 0; iteration < 200 && hi > lo; ++iteration) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (slope(mid) < 0 ? lo : hi) = mid;
  }
  auto time = [&](double s) { return std::hypot(s, hs) / vs + std::hypot(delta - s, hr) / vr; };
  return std::min(time(lo), time(hi));
}

// `key` of `node`, a list with one value per training stage (`stages` of them), each read by
// `read` from its node.
template <class T, class Read>
std::vector<T> per_stage(const io::ConfigNode& node, std::string_view key, std::size_t stages,
                         Read read) {
  const io::ConfigNode list = node.child(key);
  node.require(key, list.size() == stages,
               "expected one value per training stage (" + std::to_string(stages) + ")");
  std::vector<T> values;
  for (std::size_t i = 0; i < stages; ++i) values.push_back(read(list.at(i)));
  return values;
}

// The value for training stage `stage` (the last one for stages beyond the list).
template <class T>
T of_stage(const std::vector<T>& values, std::size_t stage) {
  return values.at(std::min(stage, values.size() - 1));
}

class Eikonal final : public Problem {
 public:
  explicit Eikonal(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {
    const io::ConfigNode domain_node = context.root.child("domain");
    if (domain_.has_time()) throw domain_node.error("time", "the eikonal equation has no time axis");
    if (domain_.space_dim() < 2)
      throw domain_node.error("lower", "the eikonal problem needs 2 or 3 space dimensions");
    const io::ConfigNode equation = context.root.child("equation");
    read_source(equation);
    const bool has_speed = read_medium(equation);
    read_weights(equation, has_speed);
    read_viscosity(equation, context.root.child_or_empty("training"));
    source_weight_ = equation.get_or("source_weight", 10.0);
    equation.require("source_weight", source_weight_ >= 0 && std::isfinite(source_weight_),
                     "expected a weight >= 0");
    equation.reject_unknown_keys();
  }

  const Domain& domain() const override { return domain_; }
  std::vector<std::string> output_names() const override {
    return {factored_ ? "tau" : "u"};
  }

  fields::SineFrequencies default_sine_frequencies() const override {
    return fields::kPdeSineFrequencies;  // a differential equation: fields/field_config.h
  }
  std::vector<LossTerm> loss_terms() const override {
    const int d = domain_.space_dim();
    LossTerm pde;
    pde.name = "pde";
    pde.batch_key = "interior";
    pde.weight = weight_;
    const bool viscous = *std::max_element(viscosity_.begin(), viscosity_.end()) > 0;
    pde.spec = viscous ? autodiff::StreamSpec::laplacian(d) : autodiff::StreamSpec::gradient(d);
    pde.sample = [this](Random& rng, Eigen::Index n) { return sample_pde(rng, n); };
    // ε and the form of the current stage: the last stage's until a stage begins.
    auto stage = std::make_shared<std::size_t>(std::numeric_limits<std::size_t>::max());
    if (viscosity_.size() > 1 || concave_viscosity_.size() > 1)
      pde.begin_stage = [stage](int index) { *stage = static_cast<std::size_t>(index); };
    pde.residual = [this, stage](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
      EikonalSetup setup = residual_setup();
      setup.viscosity = of_stage(viscosity_, *stage);
      setup.concave = of_stage(concave_viscosity_, *stage);
      return make_eikonal_residual(EikonalKind::kEikonal, x, speeds(x).cwiseInverse(),
                                   std::move(setup));
    };
    std::vector<LossTerm> terms{pde};
    if (outflow_weight_ > 0) {
      LossTerm outflow = gradient_term("outflow", "boundary", outflow_weight_);
      outflow.sample = [this](Random& rng, Eigen::Index n) {
        return domain_.sample_faces(domain_.faces(), rng, n);
      };
      outflow.residual = [this](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
        return make_eikonal_residual(EikonalKind::kOutflow, x, outward_normals(x),
                                     residual_setup());
      };
      terms.push_back(outflow);
    }
    if (interface_weight_ > 0) {
      LossTerm interface = gradient_term("interface", "interface", interface_weight_);
      interface.sample = [this](Random& rng, Eigen::Index n) {
        Eigen::MatrixXd x = domain_.sample_interior(rng, n);
        x.col(layers_.axis).setConstant(layers_.interface - interface_offset());
        return x;
      };
      interface.residual = [this](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
        Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(x.rows(), domain_.space_dim());
        normals.col(layers_.axis).setConstant(source_below() ? 1.0 : -1.0);
        EikonalSetup setup = residual_setup();
        setup.far_slowness = 1 / layers_.speeds[source_below() ? 1 : 0];
        return make_eikonal_residual(EikonalKind::kInterface, x, normals, std::move(setup));
      };
      terms.push_back(interface);
    }
    if (source_weight_ > 0) {
      LossTerm at_source;
      at_source.name = "source";
      at_source.batch_key = "source";
      at_source.weight = source_weight_;
      at_source.spec = autodiff::StreamSpec::values(d);
      const Eigen::RowVectorXd x0 = x0_.transpose();
      at_source.sample = [x0](Random&, Eigen::Index n) {
        return Eigen::MatrixXd(x0.replicate(n, 1));
      };
      at_source.residual = [this](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
        return make_eikonal_residual(EikonalKind::kSource, x, Eigen::MatrixXd(),
                                     residual_setup());
      };
      terms.push_back(at_source);
    }
    return terms;
  }

  bool known_travel_time() const { return !speed_ || constant_speed_ > 0 || exact_; }
  // Factored: the travel-time metrics come from write_outputs (see the header).
  bool has_exact() const override { return !factored_ && known_travel_time(); }

  // The exact network output: the travel time T, or τ = T/T₀ − 1 when factored (0 at x₀).
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override {
    const Eigen::VectorXd t = travel_time(x);
    if (!factored_) return t;
    Eigen::MatrixXd tau(x.rows(), 1);
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const double t0 = (x.row(p).transpose() - x0_).norm() / v0_;
      tau(p, 0) = t0 > 0 ? t(p) / t0 - 1 : 0.0;
    }
    return tau;
  }

  std::optional<double> reported_error(const OutputContext& context) const override {
    if (!factored_ || !known_travel_time()) return std::nullopt;
    return travel_time_on_grid(context).rel_l2;
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    if (!factored_ || !known_travel_time()) return;
    const TravelTimeOnGrid result = travel_time_on_grid(context);
    metrics.emplace_back("rel_l2", result.rel_l2);
    metrics.emplace_back("max_abs_err", result.max_abs_err);
    std::printf("travel time u = T0 (1 + tau): rel_l2 %.3e, max_abs_err %.3e\n", result.rel_l2,
                result.max_abs_err);
    io::PointArrays arrays;
    arrays["travel_time"] = result.u;
    arrays["exact_travel_time"] = result.exact;
    arrays["error_travel_time"] = result.u - result.exact;
    arrays["exact_tau"] = exact(result.x);
    io::write_vti(context.dir / "travel_time.vti", result.grid, arrays);
  }

 private:
  // The constructor's steps, each reading its keys of `equation` in the order of the header.
  void read_source(const io::ConfigNode& equation) {
    const int d = domain_.space_dim();
    const auto source = equation.get_list<double>("source", static_cast<std::size_t>(d));
    x0_.resize(d);
    for (int a = 0; a < d; ++a) {
      x0_(a) = source[a];
      equation.require("source", source[a] >= domain_.lower()[a] && source[a] <= domain_.upper()[a],
                       "expected a point inside the domain");
    }
  }

  // `speed` or `layers`, the speed v₀ at the source, and `exact`; true for `speed`.
  bool read_medium(const io::ConfigNode& equation) {
    const auto vars = domain_.expression_variables();
    const bool has_speed = equation.has("speed"), has_layers = equation.has("layers");
    equation.require(has_speed != has_layers, "expected exactly one of `speed` and `layers`");
    if (has_speed)
      speed_ = std::make_shared<io::Expression>(equation.get_expression("speed", vars));
    else
      read_layers(equation.child("layers"));
    const Eigen::MatrixXd x0_row = x0_.transpose();
    v0_ = speeds(x0_row)(0);
    equation.require(has_speed ? "speed" : "layers", v0_ > 0 && std::isfinite(v0_),
                     "expected a speed > 0 at the source");
    if (has_speed && speed_->is_constant()) constant_speed_ = v0_;
    if (equation.has("exact")) {
      equation.require("exact", has_speed && !speed_->is_constant(),
                       "not used: the exact solution of a constant speed or of layers is built in");
      exact_ = std::make_shared<io::Expression>(equation.get_expression("exact", vars));
    }
    return has_speed;
  }

  void read_layers(const io::ConfigNode& layers) {
    std::vector<std::string> axes{"x", "y", "z"};
    axes.resize(domain_.space_dim());
    const std::string axis = layers.get_choice("axis", axes);
    layers_.axis = static_cast<int>(std::find(axes.begin(), axes.end(), axis) - axes.begin());
    layers_.interface = layers.get<double>("interface");
    layers.require("interface",
                   layers_.interface > domain_.lower()[layers_.axis] &&
                       layers_.interface < domain_.upper()[layers_.axis],
                   "expected a plane inside the domain");
    const auto speeds = layers.get_list<double>("speeds", 2);
    for (int k = 0; k < 2; ++k) {
      layers.require("speeds", speeds[k] > 0 && std::isfinite(speeds[k]), "expected speeds > 0");
      layers_.speeds[k] = speeds[k];
    }
    layers.reject_unknown_keys();
  }

  void read_weights(const io::ConfigNode& equation, bool has_speed) {
    factored_ = equation.get_or("factored", false);
    weight_ = equation.get_or("weight", 1.0);
    equation.require("weight", weight_ > 0 && std::isfinite(weight_), "expected a weight > 0");
    source_fraction_ = equation.get_or("source_fraction", 0.25);
    equation.require("source_fraction", source_fraction_ >= 0 && source_fraction_ <= 1,
                     "expected a fraction in [0, 1]");
    interface_weight_ = equation.get_or("interface_weight", 0.0);
    equation.require("interface_weight", interface_weight_ >= 0 && std::isfinite(interface_weight_),
                     "expected a weight >= 0");
    equation.require("interface_weight", interface_weight_ == 0 || !has_speed,
                     "needs `layers`: the term is about their interface");
    outflow_weight_ = equation.get_or("outflow_weight", 1.0);
    equation.require("outflow_weight", outflow_weight_ >= 0 && std::isfinite(outflow_weight_),
                     "expected a weight >= 0");
  }

  // `viscosity` and `viscosity_form`: one value, or a list with one per training stage.
  void read_viscosity(const io::ConfigNode& equation, const io::ConfigNode& training) {
    const std::size_t stages = training.has("stages") ? training.child("stages").size() : 1;
    const auto is_list = [&](const char* key) {
      return equation.has_list(key);
    };
    viscosity_ = is_list("viscosity")
                     ? per_stage<double>(equation, "viscosity", stages,
                                         [](const io::ConfigNode& item) { return item.as<double>(); })
                     : std::vector<double>{equation.get_or("viscosity", 0.0)};
    for (double epsilon : viscosity_)
      equation.require("viscosity", epsilon >= 0 && std::isfinite(epsilon), "expected numbers >= 0");
    const std::vector<std::string> forms{"laplacian", "concave"};
    concave_viscosity_ =
        is_list("viscosity_form")
            ? per_stage<bool>(equation, "viscosity_form", stages,
                              [&](const io::ConfigNode& item) {
                                return item.as_choice(forms) == "concave";
                              })
            : std::vector<bool>{equation.get_choice("viscosity_form", forms, "laplacian") ==
                                "concave"};
  }

  // The factored run's travel time u = T₀ (1 + τ) against the exact one on the output grid.
  struct TravelTimeOnGrid {
    io::Grid grid;
    Eigen::MatrixXd x;
    Eigen::VectorXd u, exact;
    double rel_l2 = 0, max_abs_err = 0;
  };

  // One function for the per-stage error and the final metrics, so that they agree.
  TravelTimeOnGrid travel_time_on_grid(const OutputContext& context) const {
    const int d = domain_.space_dim();
    TravelTimeOnGrid result;
    result.grid = io::make_grid(domain_.lower(), domain_.upper(), context.grid);
    result.x = result.grid.points(d);
    const Eigen::VectorXd tau = context.values(result.x).col(0);
    result.u.resize(result.x.rows());
    for (Eigen::Index p = 0; p < result.x.rows(); ++p)
      result.u(p) = (result.x.row(p).transpose() - x0_).norm() / v0_ * (1 + tau(p));
    result.exact = travel_time(result.x);
    const Eigen::VectorXd error = result.u - result.exact;
    const double norm = result.exact.norm();
    result.rel_l2 = norm > 0 ? error.norm() / norm : error.norm();
    result.max_abs_err = error.cwiseAbs().maxCoeff<Eigen::PropagateNaN>();
    return result;
  }

  EikonalSetup residual_setup() const {
    EikonalSetup setup;
    setup.factored = factored_;
    setup.x0 = x0_;
    setup.v0 = v0_;
    setup.length = diameter();
    return setup;
  }

  // A term that reads values and gradients (outflow, interface); sample and residual unset.
  LossTerm gradient_term(const char* name, const char* batch_key, double weight) const {
    LossTerm term;
    term.name = name;
    term.batch_key = batch_key;
    term.weight = weight;
    term.spec = autodiff::StreamSpec::gradient(domain_.space_dim());
    return term;
  }

  bool source_below() const { return layers_.layer(x0_.data()) == 0; }
  // Interface points sit this far from the plane on the source's side (signed: towards the
  // source), so that one-sided derivatives (cusp features) are taken on that side.
  double interface_offset() const {
    const double extent = domain_.upper()[layers_.axis] - domain_.lower()[layers_.axis];
    return (source_below() ? 1e-6 : -1e-6) * extent;
  }

  // The length of the domain's diagonal.
  double diameter() const {
    double d2 = 0;
    for (int a = 0; a < domain_.space_dim(); ++a)
      d2 += (domain_.upper()[a] - domain_.lower()[a]) * (domain_.upper()[a] - domain_.lower()[a]);
    return std::sqrt(d2);
  }

  // Interior points: a fraction `source_fraction` with radius |x − x₀| uniform in [0, R] (R
  // the distance to the farthest corner, points outside redrawn), the rest uniform.
  Eigen::MatrixXd sample_pde(Random& rng, Eigen::Index n) const {
    const int d = domain_.space_dim();
    const auto near = static_cast<Eigen::Index>(std::llround(source_fraction_ * static_cast<double>(n)));
    Eigen::MatrixXd x(n, d);
    if (near < n) x.bottomRows(n - near) = domain_.sample_interior(rng, n - near);
    double reach = 0;
    for (int corner = 0; corner < (1 << d); ++corner) {
      double r2 = 0;
      for (int a = 0; a < d; ++a) {
        const double c = (corner >> a) & 1 ? domain_.upper()[a] : domain_.lower()[a];
        r2 += (c - x0_(a)) * (c - x0_(a));
      }
      reach = std::max(reach, std::sqrt(r2));
    }
    Eigen::VectorXd direction(d);
    for (Eigen::Index p = 0; p < near; ++p) {
      for (;;) {
        // A uniform direction: normal deviates (Box–Muller from the raw engine), normalized.
        for (int a = 0; a < d; ++a) direction(a) = standard_normal(rng);
        const double norm = direction.norm();
        if (!(norm > 0)) continue;
        const Eigen::VectorXd point = x0_ + (reach * uniform01(rng) / norm) * direction;
        bool inside = true;
        for (int a = 0; a < d; ++a)
          inside = inside && point(a) >= domain_.lower()[a] && point(a) <= domain_.upper()[a];
        if (inside) {
          x.row(p) = point.transpose();
          break;
        }
      }
    }
    return x;
  }

  // The outward unit normals of boundary points (a corner: the sum of its faces' normals,
  // normalized).
  Eigen::MatrixXd outward_normals(const Eigen::MatrixXd& x) const {
    const int d = domain_.space_dim();
    Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(x.rows(), d);
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      for (int a = 0; a < d; ++a) {
        if (x(p, a) <= domain_.lower()[a]) normals(p, a) = -1;
        if (x(p, a) >= domain_.upper()[a]) normals(p, a) = 1;
      }
      const double norm = normals.row(p).norm();
      if (norm > 0) normals.row(p) /= norm;
    }
    return normals;
  }

  // v at points x (n × d).
  Eigen::VectorXd speeds(const Eigen::MatrixXd& x) const {
    if (speed_) return speed_->evaluate(x);
    Eigen::VectorXd v(x.rows());
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const Eigen::RowVectorXd row = x.row(p);
      v(p) = layers_.speed(row.data());
    }
    return v;
  }

  // The exact first-arrival time at points x.
  Eigen::VectorXd travel_time(const Eigen::MatrixXd& x) const {
    if (exact_) return exact_->evaluate(x);
    const int d = domain_.space_dim();
    Eigen::VectorXd t(x.rows());
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const Eigen::RowVectorXd row = x.row(p);
      t(p) = speed_ ? (row.transpose() - x0_).norm() / constant_speed_
                    : layered_travel_time(layers_, x0_.data(), row.data(), d);
    }
    return t;
  }

  Domain domain_;
  Eigen::VectorXd x0_;
  std::shared_ptr<io::Expression> speed_, exact_;
  Layers layers_;
  double v0_ = 1, constant_speed_ = 0;
  bool factored_ = false;
  double weight_ = 1, source_weight_ = 10, outflow_weight_ = 1, source_fraction_ = 0.25;
  double interface_weight_ = 0;
  // ε and `viscosity_form: concave` per training stage, or one for all.
  std::vector<double> viscosity_{0.0};
  std::vector<bool> concave_viscosity_{false};
};

}  // namespace

std::unique_ptr<Problem> make_eikonal(const ProblemContext& context) {
  return std::make_unique<Eikonal>(context);
}

}  // namespace nfield::solvers
