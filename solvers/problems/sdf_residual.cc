// SPDX-License-Identifier: MIT
//
// The SDF residuals (sdf_residual.h) as functors of JetResidual, written once and
// templated on the scalar; the adjoints come from Jets. Each reads, per point,
// z[0] = u (value) and z[1 + a] = ∂u/∂x_a (tangent a).
#include "solvers/problems/sdf_residual.h"

#include <array>
#include <cmath>

#include "solvers/core/jet_residual.h"

namespace nfield::solvers {
namespace {

// A residual component whose square is |x| (absolute) or x² (squares): sign(x) √|x| or x.
// √|x| has no finite derivative at 0; there it is taken as 0 (the loss's own derivative,
// r̄ ∂r/∂x with r̄ ∝ r, tends to ±1 there; 0 is a subgradient).
template <typename T>
T part(const T& x, bool absolute) {
  if (!absolute) return x;
  using std::sqrt;
  const double value = scalar_of(x);
  if (value == 0) return T(0.0);
  return value < 0 ? T(-sqrt(T(-x))) : T(sqrt(x));
}

std::array<StreamRead, 4> value_and_gradient(const StreamLayout& layout) {
  return {StreamRead{StreamLayout::value(), 0}, StreamRead{layout.tangent(0), 0},
          StreamRead{layout.tangent(1), 0}, StreamRead{layout.tangent(2), 0}};
}

// r = [√w_sdf ρ(u),  √(w_normal/2) (ĝ − n),  √w_eikonal ρ(|∇u| − 1)], ĝ = ∇u/|∇u|.
class SdfSurface {
 public:
  struct PointData {
    double normal[3];
  };
  static constexpr int kReads = 4;
  static constexpr int kComponents = 5;

  SdfSurface(Eigen::MatrixXd normals, const SdfWeights& w) : normals_(std::move(normals)), w_(w) {}

  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    return value_and_gradient(layout);
  }
  PointData point(Eigen::Index index) const {
    return {{normals_(index, 0), normals_(index, 1), normals_(index, 2)}};
  }

  template <typename T>
  void operator()(const T* z, const PointData& data, T* r) const {
    const T* g = z + 1;
    // |∇u| and ĝ are not differentiable at ∇u = 0: both are constants there (ĝ = 0).
    const T norm = norm_or_flat(g, 3);
    const bool smooth = scalar_of(norm) > 1e-12;
    const double c = std::sqrt(0.5 * w_.normal);
    r[0] = std::sqrt(w_.sdf) * part(z[0], w_.absolute);
    for (int a = 0; a < 3; ++a)
      r[1 + a] = c * ((smooth ? T(g[a] / norm) : T(0.0)) - data.normal[a]);
    r[4] = std::sqrt(w_.eikonal) * part(T(norm - 1.0), w_.absolute);
  }

 private:
  Eigen::MatrixXd normals_;
  SdfWeights w_;
};

// r = [√w_eikonal ρ(|∇u| − 1),  √w_off exp(−α|u|/2)].
class SdfInterior {
 public:
  struct PointData {};
  static constexpr int kReads = 4;
  static constexpr int kComponents = 2;

  explicit SdfInterior(const SdfWeights& w) : w_(w) {}

  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    return value_and_gradient(layout);
  }
  PointData point(Eigen::Index) const { return {}; }

  template <typename T>
  void operator()(const T* z, const PointData&, T* r) const {
    using std::exp;
    const T norm = norm_or_flat(z + 1, 3);
    r[0] = std::sqrt(w_.eikonal) * part(T(norm - 1.0), w_.absolute);
    // |u| with derivative 0 at u = 0 (Ceres' abs gives ±1 there).
    r[1] = std::sqrt(w_.off_surface) * exp(-0.5 * w_.alpha * abs_or_flat(z[0]));
  }

 private:
  SdfWeights w_;
};

}  // namespace

std::unique_ptr<Residual> make_sdf_residual(Eigen::MatrixXd normals, bool surface,
                                            const SdfWeights& weights) {
  if (surface) return make_jet_residual(SdfSurface(std::move(normals), weights));
  return make_jet_residual(SdfInterior(weights));
}

}  // namespace nfield::solvers
