// SPDX-License-Identifier: MIT
//
// Hard (exactly enforced) boundary and initial conditions by an ansatz on the field's output:
// the composition u = A + D·N that the trainer's loss terms and the Solution (solution.h) both
// apply. Reading it from a `conditions:` list is read_ansatz (solvers/conditions/hard_constraints.h).
//
// A condition with `enforce: hard` is not a loss term: the network N is wrapped as
//
//     u(x) = A(x) + D(x) · N(x)                   (per output channel c: u_c = A_c + D N_c)
//
// with a base A that satisfies the hard conditions and a scalar factor D that vanishes where
// they hold, so u satisfies them for every θ:
//
//   Dirichlet on faces F (u = g):   A = g,   D = φ,   φ(x) = Π_{f∈F} ℓ_f(x),
//       ℓ_f = (x_a − lower_a)/(upper_a − lower_a) on a lower face, (upper_a − x_a)/(…) on an
//       upper one (normalized so φ ∈ [0, 1] and N keeps the scale of u).
//   Dirichlet on parts P of a geometry (domain.geometry):  A = g,  D = φ_P(x), the
//       R-function distance to those parts (solvers/geometry/geometry.h: Geometry::distance),
//       0 on them, positive inside, ∂φ/∂n = −1 there, with its exact gradient and Hessian.
//       With `saturate: s`, D = s·tanh(φ/s): the same near the parts, ≈ s deep inside. A
//       distance has ridges on the medial axis (the points with two closest boundary points;
//       a mesh's spline distance rounds them over one cell, so its Hessian is of order 1/h
//       there), and u = A + D·N hands them to N = (u − A)/D unless D flattens out before
//       them: tanh' = sech² is e^{−2φ/s}-small where φ ≫ s.
//   Wave initial data (u(x,t0) = u0, u_t(x,t0) = v0), τ = t − t0, T = t1 − t0:
//       A = u0(x) + τ v0(x),   D = ψ(τ)² with ψ = τ/T   (value only hard: A = u0, D = ψ)
//   both:  A = u0 + τ v0,   D = φ(x) ψ(τ)².
//   With a time scale s (`time_scale: s` on the hard initial value), ψ = tanh(τ/s): D still
//   vanishes to the same order at t0, but saturates at 1 for τ ≫ s, so N ≈ (u − A)/φ need
//   not grow like 1/τ² (for a mode cos(ωτ) the polynomial factor asks N ~ ω²/2 near t0,
//   hundreds for ω = 8π; the saturating one ~ s²ω²/2).
//
// The combined form is exact only for compatible data: g independent of t, u0 = g and v0 = 0
// on the hard faces (checked at load; otherwise a config error). Then A = g on the faces,
// A(·,t0) = u0, A_t(·,t0) = v0, and D, D_t vanish at t0 and D on the faces.
//
// Fading g. A = g(x) makes the ansatz exact for N = 0 whenever g is the solution itself (a
// manufactured u* given as the boundary value): the network would have nothing to learn. With
// `fade: δ` (parts of a geometry only) A(x) = g(x)·exp(−φ(x)/δ): g on the parts (φ = 0),
// fading inward over a length δ, so that away from the boundary u ≈ φ·N and the network
// carries the solution, as in a problem with zero boundary values. Its derivatives come from
// the same finite differences below (of the product, all space axes), which need φ ∈ C² (a
// mesh: `distance: smooth`, solvers/geometry/spline_distance.h). Tried first and dropped:
// g(x − φ∇φ), the boundary values carried inward along ∇φ; its Laplacian holds φ·∇³φ, which
// is of order φ/h² where a spline rounds the distance's ridge on the medial axis (hundreds in
// the bunny: a first loss of 10⁵ against 10³ for the fade).
//
// Several hard Dirichlet items are supported when they carry the same `value` expression(s)
// (compared as text, per channel): g is that expression evaluated inside the box. Different
// values on different hard faces would need a blended extension of g; they are rejected.
//
// Derivative streams. A residual reads the streams of u for its StreamLayout (value,
// tangents u⁽ⁱ⁾ = ∂u/∂vᵢ along the spec's directions vᵢ, operator streams
// u^[C] = Σᵢⱼ Cᵢⱼ ∂²u/∂vᵢ∂vⱼ). The product rule maps the network's streams, computed with
// the same layout, onto them:
//
//     u⁰    = A⁰ + D⁰ N⁰
//     u⁽ⁱ⁾  = A⁽ⁱ⁾ + D⁽ⁱ⁾ N⁰ + D⁰ N⁽ⁱ⁾
//     u^[C] = A^[C] + D^[C] N⁰ + Σᵢⱼ Cᵢⱼ (D⁽ⁱ⁾N⁽ʲ⁾ + D⁽ʲ⁾N⁽ⁱ⁾) + D⁰ N^[C]
//
// This rule is written once, templated on the scalar (ansatz_product_rule below, per point
// and channel). `apply` runs it in double, on packs of 16 points (Eigen fixed-size arrays,
// which the compiler vectorizes) and point by point for the rest: packs are what keep its cost
// small beside a training step (timings: docs/experiments.md).
//
// The adjoint is not written by hand. Every term of u − A above is one D stream times one N
// stream: the rule is bilinear in (D, N),
//
//     u_i = A_i + Σ_jk M_ijk D_k N_j,    M_ijk = ∂²u_i/∂N_j∂D_k,
//
// with coefficients that depend on the layout only (its operators C), not on the point, the
// channel, A or N. They are read off the rule by forward-mode duals (Ansatz::bilinear_terms):
// with D = e_k, the k-th unit vector in double, and N seeded as ceres::Jet<double, 8> unit
// duals, a chunk of 8 streams per pass, the dual part j of u_i is M_ijk exactly. That is
// S·⌈S/8⌉ passes per layout, S = 1 + T + Q (one chunk up to 3D + time with three operators;
// S is known only at run time, hence chunks rather than Jet<double, S>). Ansatz::streams does
// it once, beside the A and D streams (AnsatzStreams::terms), rather than on every call of the
// adjoint, a block of 128 points, whose cost it would double (timings: docs/experiments.md).
// Nothing is stored per point. The adjoint is then
//
//     N̄_j += Σ_ik M_ijk D_k ū_i,    one column product per nonzero M_ijk,
//
// the same products as the transpose written out by hand,
//
//     N̄⁰    += D⁰ ū⁰ + Σᵢ D⁽ⁱ⁾ ū⁽ⁱ⁾ + Σ_C D^[C] ū^[C]
//     N̄⁽ʲ⁾  += D⁰ ū⁽ʲ⁾ + Σ_C ū^[C] Σᵢ (Cᵢⱼ + Cⱼᵢ) D⁽ⁱ⁾
//     N̄^[C] += D⁰ ū^[C]
//
// which tests/solvers/core/ansatz_adjoint_test.cc keeps as the reference (as fast as the
// coefficient form: docs/experiments.md). A change to the rule that breaks bilinearity (a
// product of two D or two N streams) makes that test fail.
//
// The streams of A and D come from their gradient ∇ and Hessian H in input coordinates:
// a⁽ⁱ⁾ = ∇a·vᵢ, a^[C] = Σ_ab (V C Vᵀ)_ab H_ab. D is a product of closed forms (polynomials,
// and tanh with a time scale): its derivatives are exact. A is built from the config's
// expressions: a constant is exact (zero derivatives); otherwise 4th-order central
// differences with step h_a = 10⁻³ × (extent of axis a), the tensor product of the stencil
// (1, −8, 0, 8, −1)/12h for mixed second derivatives and (−1, 16, −30, 16, −1)/12h² on the
// diagonal, skipped along axes the expression does not mention. Ansatz::streams asks only
// for the Hessian entries some operator of the layout reads ((V C Vᵀ)_ab ≠ 0; the wave
// operator reads no mixed entry: 9 evaluations per point instead of 25 for a 2-D initial
// value, the same numbers otherwise). The error is about h⁴ max|∂⁵g|/30 (first) and
// h⁴ max|∂⁶g|/90 (second) plus rounding ~10 ε max|g| / h²; for
// g = sin(4πx) on [0, 1] both are below 1e-9 relative. The stencil reaches 2h outside the
// box, so the expressions must be smooth in a neighbourhood of it.
//
// Taylor streams (orders > 2) are not supported: a layout with them throws.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/config.h"
#include "io/expression.h"
#include "solvers/geometry/geometry.h"
#include "solvers/core/residual.h"

namespace nfield::solvers {

// A scalar function's value, gradient and Hessian at n points (input coordinates).
struct Jet {
  Eigen::VectorXd value;          // n
  Eigen::MatrixXd gradient;       // n × d
  std::vector<Eigen::VectorXd> hessian;  // d·d entries (row-major), each n

  static Jet constant(Eigen::Index n, int d, double c);
  Jet operator*(const Jet& other) const;
  Jet operator+(const Jet& other) const;
};

// One nonzero coefficient of the rule: u stream `u` has the term coefficient · D_d · N_n.
struct AnsatzTerm {
  int u = 0;
  int n = 0;
  int d = 0;
  double coefficient = 0;
};

// The streams of A (points × channels per stream) and D (points × 1 per stream) for one
// layout and point set, and the rule's coefficients for that layout (Ansatz::bilinear_terms).
struct AnsatzStreams {
  Streams<double> base;
  Streams<double> factor;
  std::vector<AnsatzTerm> terms;
};

// The product rule at one point and channel: u = A + D N on the streams of `layout` (value,
// tangents, operators; no Taylor streams). a, d: the point's A streams (of the channel) and
// D streams, n: N's, u: the result, each layout.count() long. T is the scalar of N and u:
// double, a pack of points (an Eigen fixed-size array, in `apply`), or ceres::Jet (for the
// coefficients M); C that of A and D, which enter as constants: double, or the same pack.
// Each term of u − A must stay one D stream times one N stream: the adjoint relies on it.
template <typename T, typename C>
void ansatz_product_rule(const StreamLayout& layout, const C* a, const C* d, const T* n, T* u) {
  u[0] = a[0] + d[0] * n[0];
  for (int i = 0; i < layout.tangents(); ++i) {
    const int k = layout.tangent(i);
    u[k] = a[k] + d[k] * n[0] + d[0] * n[k];
  }
  for (int q = 0; q < layout.operators(); ++q) {
    const int k = layout.op(q);
    T sum = a[k] + d[k] * n[0] + d[0] * n[k];
    // Σᵢⱼ Cᵢⱼ (D⁽ⁱ⁾N⁽ʲ⁾ + D⁽ʲ⁾N⁽ⁱ⁾) over the pairs i ≤ j, whose coefficient is Cᵢⱼ + Cⱼᵢ
    // off the diagonal (i = j counts D⁽ⁱ⁾N⁽ⁱ⁾ twice, as it should).
    for (const autodiff::OperatorTerm& t : layout.terms(q)) {
      const int i = layout.tangent(t.i), j = layout.tangent(t.j);
      sum += t.coefficient * (d[i] * n[j] + d[j] * n[i]);
    }
    u[k] = sum;
  }
}

class Ansatz {
 public:
  struct Dirichlet {
    std::vector<Face> faces;
    std::vector<io::Expression> values;  // one per channel
    // On a domain with a geometry: the parts instead of faces, D = φ of Geometry::distance.
    std::optional<geometry::Selection> parts{};
    // With parts and fade = δ > 0: A(x) = g(x)·exp(−φ(x)/δ) instead of g(x) (see above).
    double fade = 0;
    // With parts and saturate = s > 0: D = s·tanh(φ/s) instead of φ (see above).
    double saturate = 0;
  };
  struct Initial {
    std::vector<io::Expression> value;                    // u0, one per channel
    std::optional<std::vector<io::Expression>> velocity;  // v0 when also hard
    double time_scale = 0;  // s > 0: ψ = tanh(τ/s); 0: ψ = τ/T
  };
  Ansatz(const Domain& domain, int channels, std::optional<Dirichlet> dirichlet,
         std::optional<Initial> initial);

  int channels() const { return channels_; }
  bool has_dirichlet() const { return dirichlet_.has_value(); }
  bool has_initial() const { return initial_.has_value(); }

  // Jets of the base (one per channel) and of the factor at x.
  std::vector<Jet> base_jets(const Eigen::MatrixXd& x, bool second) const;
  // Base jets with only the Hessian entries (a, b) where hessian[a·d + b] or [b·d + a] is
  // set (row-major d × d mask; empty: no Hessian); the others stay 0. Each entry of a
  // product or sum of jets depends only on the same entry of its factors and on gradients,
  // so the computed entries equal base_jets(x, true)'s.
  std::vector<Jet> base_jets(const Eigen::MatrixXd& x, const std::vector<bool>& hessian) const;
  Jet factor_jet(const Eigen::MatrixXd& x, bool second) const;

  // A and D streams at x for `layout` (throws std::invalid_argument on Taylor streams).
  AnsatzStreams streams(const StreamLayout& layout, const Eigen::MatrixXd& x) const;
  // The nonzero M_ijk of ansatz_product_rule for `layout`, from ceres::Jet passes.
  static std::vector<AnsatzTerm> bilinear_terms(const StreamLayout& layout);
  // u streams from network streams n for points [first, first + n.points) of `s`.
  void apply(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
             const Streams<double>& n, Streams<double>& u) const;
  // n_bar += ∂(Σ ū ⊙ u)/∂n, from s.terms (from bilinear_terms when s has none).
  void adjoint(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
               const Streams<double>& u_bar, Streams<double>& n_bar) const;
  // u values at x from network values (n × channels).
  Eigen::MatrixXd values(const Eigen::MatrixXd& x, const Eigen::MatrixXd& network_values) const;

 private:
  Jet expression_jet(const io::Expression& e, const Eigen::MatrixXd& x,
                     const std::vector<bool>& hessian, bool frozen_time, bool fade = false) const;
  // exp(−φ/δ) at the rows of x (`fade`).
  Eigen::VectorXd fade_weights(const Eigen::MatrixXd& x) const;

  const Domain domain_;
  int channels_;
  std::optional<Dirichlet> dirichlet_;
  std::optional<Initial> initial_;
};

// A residual on u = A + D N: transforms the network streams before `inner` and chains its
// adjoint back. A and D streams are precomputed for the point set it is built for.
class AnsatzResidual final : public Residual {
 public:
  AnsatzResidual(std::shared_ptr<const Ansatz> ansatz, std::unique_ptr<Residual> inner,
                 const StreamLayout& layout, const Eigen::MatrixXd& points);
  int components() const override { return inner_->components(); }
  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override;
  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override;

 private:
  std::shared_ptr<const Ansatz> ansatz_;
  std::unique_ptr<Residual> inner_;
  AnsatzStreams streams_;
};

// The loss terms with each residual wrapped in AnsatzResidual (unchanged when ansatz is null).
std::vector<LossTerm> with_ansatz(std::vector<LossTerm> terms,
                                  std::shared_ptr<const Ansatz> ansatz);

// Streams of u from a function giving the network's streams (same signature as
// StreamEvaluator in grid_output.h; unchanged when ansatz is null).
using NetworkStreams =
    std::function<Streams<double>(const StreamLayout&, const Eigen::MatrixXd&)>;
NetworkStreams with_ansatz(NetworkStreams network, std::shared_ptr<const Ansatz> ansatz);

}  // namespace nfield::solvers
