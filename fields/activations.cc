// SPDX-License-Identifier: MIT
#include "fields/activations.h"

#include <cmath>
#include <functional>

#include "io/registry.h"

namespace nfield::fields {
namespace {

using autodiff::ElementwiseFunction;
using autodiff::Matrix;
template <typename Scalar>
using Ref = Eigen::Ref<const Matrix<Scalar>>;

template <typename Scalar>
void size_tables(std::vector<Matrix<Scalar>>& tables, int max_order, const Ref<Scalar>& z) {
  tables.resize(max_order + 1);
  for (auto& t : tables) t.resize(z.rows(), z.cols());
}

template <typename Scalar>
class Sine final : public ElementwiseFunction<Scalar> {
 public:
  explicit Sine(double omega) : omega_(omega) {}
  void derivatives(const Ref<Scalar>& z, int max_order,
                   std::vector<Matrix<Scalar>>& tables) const override {
    size_tables(tables, max_order, z);
    const Scalar w = static_cast<Scalar>(omega_);
    tables[0].array() = (w * z.array()).sin();
    if (max_order == 0) return;
    tables[1].array() = (w * z.array()).cos();
    Scalar scale = 1;
    for (int m = 1; m <= max_order; ++m) {
      scale *= w;
      // σ⁽ᵐ⁾ = ωᵐ · (s, c, −s, −c)[m mod 4]
      const Scalar sign = (m % 4 == 2 || m % 4 == 3) ? Scalar(-1) : Scalar(1);
      const Matrix<Scalar>& base = (m % 2 == 0) ? tables[0] : tables[1];
      if (m >= 2) tables[m].array() = (sign * scale) * base.array();
    }
    tables[1] *= w;
  }

 private:
  double omega_;
};

// Derivatives that are polynomials in g(z): σ⁽ᵐ⁾ = pₘ(g), with g' = h(g) a polynomial.
// p_{m+1} = pₘ' · h.
std::vector<std::vector<double>> derivative_polynomials(std::vector<double> p0,
                                                        const std::vector<double>& h,
                                                        int max_order) {
  std::vector<std::vector<double>> p{std::move(p0)};
  for (int m = 0; m < max_order; ++m) {
    const auto& prev = p.back();
    std::vector<double> derivative(prev.size() > 1 ? prev.size() - 1 : 1, 0.0);
    for (size_t k = 1; k < prev.size(); ++k) derivative[k - 1] = k * prev[k];
    std::vector<double> next(derivative.size() + h.size() - 1, 0.0);
    for (size_t a = 0; a < derivative.size(); ++a)
      for (size_t b = 0; b < h.size(); ++b) next[a + b] += derivative[a] * h[b];
    p.push_back(std::move(next));
  }
  return p;
}

template <typename Scalar>
void horner(const std::vector<double>& poly, const Matrix<Scalar>& g, Matrix<Scalar>& out) {
  out.setConstant(static_cast<Scalar>(poly.back()));
  for (size_t k = poly.size() - 1; k-- > 0;)
    out.array() = out.array() * g.array() + static_cast<Scalar>(poly[k]);
}

template <typename Scalar>
class Tanh final : public ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Ref<Scalar>& z, int max_order,
                   std::vector<Matrix<Scalar>>& tables) const override {
    size_tables(tables, max_order, z);
    tables[0].array() = z.array().tanh();
    // d/dz tanh = 1 − tanh²
    const auto polys = derivative_polynomials({0.0, 1.0}, {1.0, 0.0, -1.0}, max_order);
    for (int m = 1; m <= max_order; ++m) horner(polys[m], tables[0], tables[m]);
  }
};

template <typename Scalar>
class Softplus final : public ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Ref<Scalar>& z, int max_order,
                   std::vector<Matrix<Scalar>>& tables) const override {
    size_tables(tables, max_order, z);
    tables[0].array() = z.array().max(Scalar(0)) + (-z.array().abs()).exp().log1p();
    if (max_order == 0) return;
    Matrix<Scalar> sigmoid = (Scalar(1) + (-z.array()).exp()).inverse().matrix();
    // d/dz sigmoid = s − s²; σ' = s
    const auto polys = derivative_polynomials({0.0, 1.0}, {0.0, 1.0, -1.0}, max_order - 1);
    for (int m = 1; m <= max_order; ++m) horner(polys[m - 1], sigmoid, tables[m]);
  }
};

template <typename Scalar>
class Relu final : public ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Ref<Scalar>& z, int max_order,
                   std::vector<Matrix<Scalar>>& tables) const override {
    size_tables(tables, max_order, z);
    tables[0].array() = z.array().max(Scalar(0));
    if (max_order >= 1)  // a plain loop: Eigen does not vectorise a cast of a comparison
      for (Eigen::Index j = 0; j < z.cols(); ++j) {
        const Scalar* in = z.col(j).data();
        Scalar* step = tables[1].col(j).data();
        for (Eigen::Index i = 0; i < z.rows(); ++i) step[i] = in[i] > Scalar(0) ? Scalar(1) : Scalar(0);
      }
    for (int m = 2; m <= max_order; ++m) tables[m].setZero();
  }
};

template <typename Scalar>
class Identity final : public ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Ref<Scalar>& z, int max_order,
                   std::vector<Matrix<Scalar>>& tables) const override {
    size_tables(tables, max_order, z);
    tables[0] = z;
    if (max_order >= 1) tables[1].setOnes();
    for (int m = 2; m <= max_order; ++m) tables[m].setZero();
  }
};

struct ActivationEntry {
  std::function<std::unique_ptr<ElementwiseFunction<float>>(const ActivationSpec&)> make_float;
  std::function<std::unique_ptr<ElementwiseFunction<double>>(const ActivationSpec&)> make_double;
};

template <template <typename> class Function>
ActivationEntry entry() {
  return {[](const ActivationSpec&) { return std::make_unique<Function<float>>(); },
          [](const ActivationSpec&) { return std::make_unique<Function<double>>(); }};
}

void register_activations(Registry<ActivationEntry>& registry) {
  registry.add("sine", {[](const ActivationSpec& s) { return std::make_unique<Sine<float>>(s.frequency); },
                        [](const ActivationSpec& s) { return std::make_unique<Sine<double>>(s.frequency); }});
  registry.add("tanh", entry<Tanh>());
  registry.add("softplus", entry<Softplus>());
  registry.add("relu", entry<Relu>());
  registry.add("identity", entry<Identity>());
}

const Registry<ActivationEntry>& activations() {
  static const Registry<ActivationEntry> registry = [] {
    Registry<ActivationEntry> r("activation");
    register_activations(r);
    return r;
  }();
  return registry;
}

}  // namespace

template <>
std::unique_ptr<ElementwiseFunction<float>> make_activation<float>(const ActivationSpec& spec) {
  return activations().at(spec.name).make_float(spec);
}
template <>
std::unique_ptr<ElementwiseFunction<double>> make_activation<double>(const ActivationSpec& spec) {
  return activations().at(spec.name).make_double(spec);
}

std::vector<std::string> activation_names() { return activations().names(); }

}  // namespace nfield::fields
