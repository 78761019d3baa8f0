// SPDX-License-Identifier: MIT
//
// Helmholtz: Δu + k²u = f in a box of 1–3 space dimensions (no time axis).
//
// Real case (one output channel u):
//
//   problem: helmholtz
//   equation:
//     wavenumber: 1                        # k >= 0
//     source: "(1 - 17*pi^2)*sin(pi*x)*sin(4*pi*y)"   # f
//     exact: "sin(pi*x)*sin(4*pi*y)"       # optional: error metrics
//     weight: 1                            # optional: weight of the "pde" loss term
//   conditions:
//     - {on: boundary, type: dirichlet, value: "0"}
//
// The residual (loss term "pde", batch `interior`) is r = Δu + k²u − f, from the value and
// Laplacian streams.
//
// Complex case (`complex: true`): two output channels u = u_re + i u_im ("u_re", "u_im"),
// time convention e^{−iωt} (outgoing waves ~ e^{+ikr}). The residual has two components, the
// real and imaginary parts of the complex residual; every complex coefficient c multiplies
// u as (Re c·u_re − Im c·u_im) + i (Im c·u_re + Re c·u_im). Two sources:
//
//   - `source`: one expression (real f) or a list [f_re, f_im]; `exact` likewise.
//   - no `source`: a point source, after the SIREN paper (Sitzmann et al. 2020, Sec. 4.3),
//     a normalized Gaussian of width σ at x₀,
//
//         f(x) = −e^{k²σ²/2} (2πσ²)^{−d/2} exp(−|x − x₀|² / (2σ²)).
//
//     The factor e^{k²σ²/2} undoes the Gaussian's damping of the radiated wave (its Fourier
//     transform at |ξ| = k is e^{−k²σ²/2}), so that for |x − x₀| ≳ 4σ the free-space solution
//     IS the Green's function of Δu + k²u = −δ (to e^{−8} relative, falling as a Gaussian):
//
//         1D  G = (i/2k) e^{ik|x|}      2D  G = (i/4) H₀⁽¹⁾(k r)      3D  G = e^{ikr}/(4πr).
//
//     exact() is the free-space solution of the smoothed source itself: G for r ≥ 8σ, and the
//     radial convolution u(r) = −∫ f(s) s^{d−1} M(r, s) ds (M(r, s) the integral of G over
//     the sphere of radius s about x₀, seen from distance r; by the addition theorem, in 2D
//     M = 2π (i/4) J₀(k r<) H₀⁽¹⁾(k r>), r< and r> the smaller and larger of r, s) by
//     Gauss–Legendre quadrature inside: finite at x₀, equal to G away from it.
//
//         source_center: [0, 0]       # x₀ (default: the origin); must lie in the domain
//         source_width: 0.05          # σ
//         source_weight: 1            # weight of the "pde_source" term (default: weight);
//                                     # 0 drops that term
//         source_sample_width: 0.1    # std of its points around x₀ (default 2σ)
//         error_exclude_radius: 0.1   # error metrics skip |x − x₀| < this (default 0.1)
//         frame: domain               # or source: coordinates relative to x₀ (below)
//
//     `frame: source` poses the same problem in coordinates relative to the source, x′ = x − x₀:
//     the box becomes [lower − x₀, upper − x₀] (with its absorbing layer and conditions) and
//     the source sits at the origin. The solution is the same function of x′, so a field, its
//     outputs and its grids see x′, and so do expressions in `conditions`. Why: over a family
//     of sources drawn anywhere (equation.family.draw: source_center), the free-space part of
//     every instance is then one and the same function, G(|x′|); only the layer differs. A
//     learned initialisation (training.meta) or a shared network can carry what the instances
//     share; in the box's own frame, a wave centred somewhere else each time, no single θ can.
//
//     The Gaussian is too narrow for uniform points to see, so a second loss term
//     "pde_source" evaluates the same residual on points drawn from a normal distribution
//     N(x₀, source_sample_width²) (those outside the domain redrawn). Its point count is the
//     batch key `source`: training.batch must have an entry `source` (e.g. {interior: 4096,
//     boundary: 512, source: 512}).
//
// Perfectly matched layer (complex case only):
//
//         pml_width: 0.5              # w (default 0: no layer)
//         pml_strength: 100           # a (default 5k, as in the SIREN reference code)
//
//   The layer is the outer band of width w INSIDE the domain box: along each axis j the
//   points with lower_j ≤ x_j < lower_j + w or upper_j − w < x_j ≤ upper_j (so [−1, 1]² with
//   w = 0.5 leaves the physical region [−0.5, 0.5]²). There coordinates are stretched,
//   ∂/∂x_j → (1/e_j) ∂/∂x_j with
//
//       e_j = 1 + i s_j(x_j)/k,   s_j = a (δ_j / w)²,   δ_j = the depth into the layer along j,
//
//   which damps an outgoing wave e^{ikx} by exp(−∫ s dx) (e^{−a w/3} across the layer) and
//   leaves it unchanged where δ = 0. Multiplied by P = Π_j e_j the equation reads
//
//       Σ_j ∂_j((P/e_j²) ∂_j u) + P k² u = P f        (2D: ∂x((e_y/e_x)∂x u) + ∂y((e_x/e_y)∂y u)
//                                                       + e_x e_y k² u = e_x e_y f)
//
//   and since e_j depends on x_j alone, Σ_j [(P/e_j²) u_jj − (P e_j'/e_j³) u_j] + P k² u = P f:
//   a linear residual in u, u_j, u_jj with complex coefficients that vary from point to
//   point. The pass carries one operator stream per axis (C = e_j e_jᵀ, i.e. u_jj) besides
//   the gradient tangents: 1 + d + d streams. Outside the layer P = e_j = 1 and the residual
//   is Δu + k²u − f.
//
//         pml_residual: divided       # (default) the residual is the above over P:
//                                     #   Σ_j [u_jj/e_j² − (e_j'/e_j³) u_j] + k² u − f
//                                     # multiplied: the above as written
//
//   Both have the same zeros, but the multiplied form scales the residual by |P|, up to
//   |1 + i a/k|² = 26 in the layer's corners (a = 100, k = 20), so its squared loss weights the
//   layer up to ~700 times the physical region and training spends itself there
//   (configs/helmholtz_pml.yaml: docs/experiments.md). Divided, the coefficients are
//   bounded by their values outside. A Dirichlet condition u = 0 on the outer faces (conditions:) closes the
//   layer; what it reflects comes back damped by e^{−2aw/3}.
//   error_mask() leaves out the layer and the disk around the source.
#include <cmath>
#include <complex>
#include <numbers>

#include "solvers/conditions/condition_values.h"
#include "solvers/conditions/conditions.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = std::numbers::pi;

// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n).
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.resize(n);
  weights.resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 1;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double step = p1 / dp;
      z -= step;
      if (std::abs(step) < 1e-15) break;
    }
    nodes[i] = z;
    weights[i] = 2 / ((1 - z * z) * dp * dp);
  }
}

// H₀⁽¹⁾(z) = J₀(z) + i Y₀(z), z > 0.
Complex hankel0(double z) { return {std::cyl_bessel_j(0.0, z), std::cyl_neumann(0.0, z)}; }

// Free-space Green's function of Δu + k²u = −δ in d dimensions at distance r > 0.
Complex green(int d, double k, double r) {
  const Complex i(0, 1);
  if (d == 1) return i / (2 * k) * std::exp(i * k * r);
  if (d == 2) return i / 4.0 * hankel0(k * r);
  return std::exp(i * k * r) / (4 * kPi * r);
}

// The integral of G(|x − y|) over the sphere |y| = s for |x| = r (the "spherical mean" times
// the sphere's measure; in 1D the two points ±s).
Complex sphere_integral(int d, double k, double r, double s) {
  const Complex i(0, 1);
  const double lo = std::min(r, s), hi = std::max(r, s);
  if (d == 1) return i / k * std::exp(i * k * hi) * std::cos(k * lo);
  if (d == 2) return 2 * kPi * (i / 4.0) * std::cyl_bessel_j(0.0, k * lo) * hankel0(k * hi);
  if (lo == 0) return std::exp(i * k * hi) / hi;
  return std::sin(k * lo) * std::exp(i * k * hi) / (k * lo * hi);
}

// Depth of x into the layer [lower, lower + w) ∪ (upper − w, upper], and its derivative
// d(depth)/dx (−1 in the lower band, +1 in the upper band, 0 outside).
std::pair<double, double> layer_depth(double x, double lower, double upper, double w) {
  if (w <= 0) return {0, 0};
  if (x < lower + w) return {lower + w - x, -1};
  if (x > upper - w) return {x - (upper - w), 1};
  return {0, 0};
}

class Helmholtz final : public Problem, public MasksError {
 public:
  explicit Helmholtz(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {
    if (domain_.has_time())
      throw context.root.child("domain").error("time", "the Helmholtz equation has no time axis");
    const io::ConfigNode equation = context.root.child("equation");
    const auto vars = domain_.expression_variables();
    const int d = domain_.space_dim();
    k_ = equation.get_nonnegative<double>("wavenumber");
    complex_ = equation.get_or("complex", false);
    weight_ = equation.get_or("weight", 1.0);
    equation.require("weight", weight_ >= 0, "expected a weight >= 0");
    const int channels = output_dim();
    const std::string frame = equation.get_or("frame", std::string("domain"));
    equation.require("frame", frame == "domain" || frame == "source", "expected domain or source");
    const bool source_frame = frame == "source";
    equation.require("frame", !source_frame || (complex_ && !equation.has("source")),
                     "frame: source needs the point source (complex: true and no `source`)");

    if (!complex_) {
      source_ = channel_expressions(equation, "source", domain_, 1);
      if (equation.has("exact")) exact_ = channel_expressions(equation, "exact", domain_, 1);
    } else {
      if (equation.has("source")) {
        source_ = channel_expressions(equation, "source", domain_, channels);
        if (equation.has("exact")) exact_ = channel_expressions(equation, "exact", domain_, channels);
      } else {
        read_point_source(equation, source_frame);
      }
    }
    pml_width_ = equation.get_or("pml_width", 0.0);
    equation.require("pml_width", pml_width_ >= 0, "expected a width >= 0");
    equation.require("pml_width", pml_width_ == 0 || complex_,
                     "the absorbing layer stretches coordinates into the complex plane: it needs "
                     "complex: true");
    for (int a = 0; a < d; ++a)
      equation.require("pml_width", 2 * pml_width_ < domain_.upper()[a] - domain_.lower()[a],
                       "expected 2 * pml_width < the domain's extent along every axis");
    pml_strength_ = equation.get_or("pml_strength", 5 * k_);
    equation.require("pml_strength", pml_strength_ >= 0 && std::isfinite(pml_strength_),
                     "expected a strength >= 0");
    if (pml_width_ > 0) equation.require("wavenumber", k_ > 0, "the layer needs a wavenumber k > 0");
    const std::string form = equation.get_or("pml_residual", "divided");
    equation.require("pml_residual", form == "divided" || form == "multiplied",
                     "expected divided or multiplied");
    pml_divided_ = form == "divided";
    equation.reject_unknown_keys();
    // (read_conditions rejects the empty mapping child_or_empty gives for a missing section.)
    if (context.root.has("conditions")) {
      ConditionReading reading;
      reading.outputs = output_names();
      conditions_ = condition_terms(read_conditions(context.root.child("conditions"), domain_, reading), domain_);
    }
  }

  const Domain& domain() const override { return domain_; }
  int output_dim() const override { return complex_ ? 2 : 1; }
  std::vector<std::string> output_names() const override {
    if (complex_) return {"u_re", "u_im"};
    return {"u"};
  }

  fields::SineFrequencies default_sine_frequencies() const override {
    return fields::kPdeSineFrequencies;  // a differential equation: fields/field_config.h
  }
  std::vector<LossTerm> loss_terms() const override {
    LossTerm pde;
    pde.name = "pde";
    pde.batch_key = "interior";
    pde.weight = weight_;
    pde.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    const int d = domain_.space_dim();
    if (pml_width_ > 0) {
      pde.spec = autodiff::StreamSpec::gradient(d);
      for (int a = 0; a < d; ++a) {
        Eigen::MatrixXd c = Eigen::MatrixXd::Zero(d, d);
        c(a, a) = 1;
        pde.spec.add_operator(c);
      }
    } else {
      pde.spec = autodiff::StreamSpec::laplacian(d);
    }
    pde.residual = [this, layout = autodiff::StreamLayout(pde.spec)](const Eigen::MatrixXd& x) {
      return residual(layout, x);
    };
    std::vector<LossTerm> terms{pde};
    if (point_source_ && source_weight_ > 0) {
      LossTerm near = pde;
      near.name = "pde_source";
      near.batch_key = "source";
      near.weight = source_weight_;
      near.sample = [this](Random& rng, Eigen::Index n) { return sample_near_source(rng, n); };
      terms.push_back(near);
    }
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    return terms;
  }

  bool has_exact() const override { return point_source_ || !exact_.empty(); }

  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override {
    if (!point_source_) return evaluate_channels(exact_, x);
    Eigen::MatrixXd u(x.rows(), 2);
    for (Eigen::Index n = 0; n < x.rows(); ++n) {
      const Complex g = point_source_solution((x.row(n).transpose() - center_).norm());
      u(n, 0) = g.real();
      u(n, 1) = g.imag();
    }
    return u;
  }

  Eigen::Array<bool, Eigen::Dynamic, 1> error_mask(const Eigen::MatrixXd& x) const override {
    Eigen::Array<bool, Eigen::Dynamic, 1> mask(x.rows());
    const int d = domain_.space_dim();
    for (Eigen::Index n = 0; n < x.rows(); ++n) {
      bool keep = true;
      for (int a = 0; a < d; ++a)
        keep = keep && layer_depth(x(n, a), domain_.lower()[a], domain_.upper()[a], pml_width_).first == 0;
      if (point_source_) keep = keep && (x.row(n).transpose() - center_).norm() >= exclude_radius_;
      mask(n) = keep;
    }
    return mask;
  }

 private:
  // The point source's keys (complex, no `source`); with `frame: source` the box moves by −x₀.
  void read_point_source(const io::ConfigNode& equation, bool source_frame) {
    const int d = domain_.space_dim();
    point_source_ = true;
    equation.require("wavenumber", k_ > 0, "the point source needs a wavenumber k > 0");
    equation.require("exact", !equation.has("exact"),
                     "not used with the point source: the reference is its free-space "
                     "solution (the Green's function away from the source)");
    center_ = Eigen::VectorXd::Zero(d);
    if (equation.has("source_center")) {
      const auto c = equation.get_list<double>("source_center", static_cast<std::size_t>(d));
      for (int a = 0; a < d; ++a) {
        center_(a) = c[a];
        equation.require("source_center", c[a] >= domain_.lower()[a] && c[a] <= domain_.upper()[a],
                         "expected a point inside the domain");
      }
    }
    width_ = equation.get_or("source_width", 0.05);
    equation.require("source_width", width_ > 0 && std::isfinite(width_), "expected a width > 0");
    sample_width_ = equation.get_or("source_sample_width", 2 * width_);
    equation.require("source_sample_width", sample_width_ > 0 && std::isfinite(sample_width_),
                     "expected a width > 0");
    source_weight_ = equation.get_or("source_weight", weight_);
    equation.require("source_weight", source_weight_ >= 0, "expected a weight >= 0");
    exclude_radius_ = equation.get_or("error_exclude_radius", 0.1);
    equation.require("error_exclude_radius", exclude_radius_ >= 0, "expected a radius >= 0");
    if (source_frame) {
      std::vector<double> lower = domain_.lower(), upper = domain_.upper();
      for (int a = 0; a < d; ++a) {
        lower[static_cast<std::size_t>(a)] -= center_(a);
        upper[static_cast<std::size_t>(a)] -= center_(a);
      }
      domain_ = Domain(std::move(lower), std::move(upper));
      center_.setZero();
    }
    amplitude_ = -std::exp(0.5 * k_ * k_ * width_ * width_) * std::pow(2 * kPi * width_ * width_, -0.5 * d);
  }

  // The source f at points x (n × components).
  Eigen::MatrixXd source_values(const Eigen::MatrixXd& x) const {
    if (!point_source_) return evaluate_channels(source_, x);
    Eigen::MatrixXd f = Eigen::MatrixXd::Zero(x.rows(), 2);
    const double inv = 1 / (2 * width_ * width_);
    for (Eigen::Index n = 0; n < x.rows(); ++n)
      f(n, 0) = amplitude_ * std::exp(-(x.row(n).transpose() - center_).squaredNorm() * inv);
    return f;
  }

  std::unique_ptr<Residual> residual(const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) const {
    const int d = domain_.space_dim();
    const Eigen::Index n = x.rows();
    const Eigen::MatrixXd f = source_values(x);
    const double k2 = k_ * k_;
    std::vector<LinearResidual::Term> terms;
    if (pml_width_ <= 0) {
      // Δu + k²u − f, channel by channel.
      for (int c = 0; c < output_dim(); ++c) {
        terms.push_back({c, layout.op(0), c, Eigen::VectorXd::Ones(1)});
        if (k2 != 0) terms.push_back({c, layout.value(), c, Eigen::VectorXd::Constant(1, k2)});
      }
      return std::make_unique<LinearResidual>(std::move(terms), f);
    }
    // Stretched operator: per-point complex coefficients of u_jj (operator stream j), u_j
    // (tangent j) and u, and the right-hand side P f.
    std::vector<Eigen::VectorXcd> second(d, Eigen::VectorXcd(n)), first(d, Eigen::VectorXcd(n));
    Eigen::VectorXcd zeroth(n);
    Eigen::MatrixXd rhs(n, 2);
    std::vector<Complex> e(d), de(d);
    for (Eigen::Index p = 0; p < n; ++p) {
      Complex product = 1;
      for (int a = 0; a < d; ++a) {
        const auto [depth, sign] = layer_depth(x(p, a), domain_.lower()[a], domain_.upper()[a], pml_width_);
        const double s = pml_strength_ * depth * depth / (pml_width_ * pml_width_);
        const double ds = 2 * pml_strength_ * depth * sign / (pml_width_ * pml_width_);
        e[a] = Complex(1, s / k_);
        de[a] = Complex(0, ds / k_);
        product *= e[a];
      }
      // The divided form is the multiplied one over P (see the header): same zeros, but
      // coefficients bounded by those outside the layer instead of growing as |P|.
      const Complex scale = pml_divided_ ? Complex(1) : product;
      for (int a = 0; a < d; ++a) {
        second[a](p) = scale / (e[a] * e[a]);
        first[a](p) = -scale * de[a] / (e[a] * e[a] * e[a]);
      }
      zeroth(p) = scale * k2;
      const Complex fp = scale * Complex(f(p, 0), f(p, 1));
      rhs(p, 0) = fp.real();
      rhs(p, 1) = fp.imag();
    }
    // c·u = (Re c u_re − Im c u_im) + i (Im c u_re + Re c u_im).
    auto add = [&terms](int stream, const Eigen::VectorXcd& c) {
      const Eigen::VectorXd re = c.real(), im = c.imag();
      terms.push_back({0, stream, 0, re});
      terms.push_back({1, stream, 1, re});
      if (!im.isZero(0)) {
        terms.push_back({0, stream, 1, -im});
        terms.push_back({1, stream, 0, im});
      }
    };
    for (int a = 0; a < d; ++a) {
      add(layout.op(a), second[a]);
      if (!first[a].isZero(0)) add(layout.tangent(a), first[a]);
    }
    if (k2 != 0) add(layout.value(), zeroth);
    return std::make_unique<LinearResidual>(std::move(terms), rhs);
  }

  // Normal around the source with std source_sample_width, redrawn outside the domain.
  Eigen::MatrixXd sample_near_source(Random& rng, Eigen::Index n) const {
    const int d = domain_.space_dim();
    Eigen::MatrixXd x(n, d);
    for (Eigen::Index p = 0; p < n; ++p) {
      for (int attempt = 0;; ++attempt) {
        bool inside = true;
        for (int a = 0; a < d; ++a) {
          // Box–Muller from the raw engine (reproducible from the seed).
          const double u1 = 1 - uniform01(rng), u2 = uniform01(rng);
          x(p, a) = center_(a) + sample_width_ * std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
          inside = inside && x(p, a) >= domain_.lower()[a] && x(p, a) <= domain_.upper()[a];
        }
        if (inside) break;
        if (attempt > 1000) {  // a source far outside any likely draw: fall back to uniform
          x.row(p) = domain_.sample_interior(rng, 1).row(0);
          break;
        }
      }
    }
    return x;
  }

  // Free-space solution of the smoothed point source at distance r from its center.
  Complex point_source_solution(double r) const {
    const int d = domain_.space_dim();
    const double reach = 8 * width_;  // the Gaussian's mass beyond: e^{−32}
    if (r >= reach) return green(d, k_, r);
    static const auto rule = [] {
      std::pair<std::vector<double>, std::vector<double>> nw;
      gauss_legendre(20, nw.first, nw.second);
      return nw;
    }();
    const auto& [nodes, weights] = rule;
    // The integrand has a kink at s = r and, in 2D, a logarithm at s = 0 in H₀(k s) for s > r:
    // panels [0, r], then [r, 2r], [2r, 4r], … up to the reach, each Gauss–Legendre.
    r = std::max(r, reach * 1e-12);  // u is continuous at the center
    std::vector<double> edges{0, r};
    while (edges.back() < reach) edges.push_back(std::min(2 * edges.back(), reach));
    const double inv = 1 / (2 * width_ * width_);
    // u = G ∗ (−f): G answers −δ.
    Complex sum = 0;
    for (size_t panel = 0; panel + 1 < edges.size(); ++panel) {
      const double a = edges[panel], b = edges[panel + 1];
      for (size_t q = 0; q < nodes.size(); ++q) {
        const double s = 0.5 * (a + b) + 0.5 * (b - a) * nodes[q];
        const double radial = -amplitude_ * std::exp(-s * s * inv) * std::pow(s, d - 1);
        sum += 0.5 * (b - a) * weights[q] * radial * sphere_integral(d, k_, r, s);
      }
    }
    return sum;
  }

  Domain domain_;
  double k_ = 0;
  bool complex_ = false;
  double weight_ = 1;
  std::vector<io::Expression> source_, exact_;
  // Point source.
  bool point_source_ = false;
  Eigen::VectorXd center_;
  double width_ = 0.05, sample_width_ = 0.1, source_weight_ = 1, exclude_radius_ = 0.1;
  double amplitude_ = 0;
  // Perfectly matched layer.
  double pml_width_ = 0, pml_strength_ = 0;
  bool pml_divided_ = true;
  std::vector<LossTerm> conditions_;
};

}  // namespace

std::unique_ptr<Problem> make_helmholtz(const ProblemContext& context) {
  return std::make_unique<Helmholtz>(context);
}

}  // namespace nfield::solvers
