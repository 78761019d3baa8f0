// SPDX-License-Identifier: MIT
//
// A reference evaluator of fields::Field written independently of autodiff/: it reads the
// flat parameter vector of a Field<double> and evaluates the network on any scalar type,
// in particular nested ceres::Jet, one point at a time. The tests compare the derivative
// streams of the library against it.
//
// Layout read (fields/field.h, fields/dense.h, fields/encodings.h):
//   encoding   [x if positional and include_input, sin(x Bᵀ), cos(x Bᵀ)], B = encoding_matrix()
//              cusp: [x, |x_a − c_k| for the planes c_k of the cusp options' at]
//              integrated_positional: input [μ (k), σ² (k)], k = d/2: [μ if include_input,
//              sin(2ˡπ μᵢ) e^{−4ˡπ²σᵢ²/2} for l < L, i < k (octave-major), then the same with
//              cos], written here from the definition in fields/integrated_positional.h
//              hash_grid: [x if include_input, per level the interpolation of the cell's
//              corner rows], written here
//              from the definition in fields/hash_grid.h (only the level sizes come from
//              fields::hash_grid_levels); its tables come first in the parameters
//   hidden l   z = W a + b (W out × in column-major, then b), y = σ_l(z)
//              siren: σ_l = sin(ω_l ·), ω_0 = first_omega, ω_l = hidden_omega for l > 0
//              mlp:   σ_l = `activation` (sine with frequency hidden_omega)
//   output     z = W a + b
//   bacon      written here from fields/bacon.h (only the fixed filter frequencies and the
//              head layers come from fields::bacon_filter_frequencies / bacon_options):
//              z₀ = sin(Ω₀ x + φ₀), zᵢ = sin(Ωᵢ x + φᵢ) ⊙ (Wᵢ zᵢ₋₁ + bᵢ), the chosen scale's
//              head H z_l + c; parameters per layer [Wᵢ, bᵢ (i ≥ 1)], φᵢ, then the heads
//   acorn      written here from fields/acorn.h (only the block tree comes from the options):
//              the block's encoder input [q, sin(2ᵏπq), cos(2ᵏπq)] through the ReLU encoder
//              to its feature grid (in double: it does not depend on x inside a block), the
//              multilinear interpolation of the grid at the point, then the decoder as an
//              mlp; the encoder's parameters come first
//
// Activations known here are written in closed form with ceres' jet functions. An activation
// registered later and not known here is applied through the library's own derivative
// tables σ⁽ᵐ⁾(z⁰) by its (exact, since nilpotent) Taylor expansion on the jet; the tables
// themselves are checked against finite differences in activation_tables_test.cc, so such
// an activation is still fully tested without new test code.
#pragma once

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "fields/acorn.h"
#include "fields/activations.h"
#include "fields/bacon.h"
#include "fields/field.h"
#include "fields/hash_grid.h"
#include "io/text.h"
#include "tests/testing/encoding_options.h"

namespace nfield::testutil {

// ---------------------------------------------------------------------------------------
// Nested jets.

template <typename T>
struct JetInfo {
  static constexpr bool is_jet = false;
  static constexpr int depth = 0;
};
template <typename T, int N>
struct JetInfo<ceres::Jet<T, N>> {
  static constexpr bool is_jet = true;
  static constexpr int depth = 1 + JetInfo<T>::depth;
  using Inner = T;
};

// The constant c as a (nested) jet: every infinitesimal part zero.
template <typename T>
T constant(double c) {
  if constexpr (!JetInfo<T>::is_jet) {
    return static_cast<T>(c);
  } else {
    using Inner = typename JetInfo<T>::Inner;
    T r;
    r.a = constant<Inner>(c);
    for (int i = 0; i < r.v.size(); ++i) r.v[i] = constant<Inner>(0.0);
    return r;
  }
}

// The real part of a (nested) jet.
template <typename T>
double value_of(const T& x) {
  if constexpr (!JetInfo<T>::is_jet) {
    return static_cast<double>(x);
  } else {
    return value_of(x.a);
  }
}

// τ as a nested jet of one variable at every level (N = 1): τ = τ₁ + … + τ_D, so the part
// ∂ᴰ/∂τ₁…∂τ_D of f(τ) is f⁽ᴰ⁾. Seeded at value v.
template <typename T>
T taylor_variable(double v) {
  if constexpr (!JetInfo<T>::is_jet) {
    return static_cast<T>(v);
  } else {
    using Inner = typename JetInfo<T>::Inner;
    T r = constant<T>(0.0);
    r.a = taylor_variable<Inner>(v);
    r.v[0] = constant<Inner>(1.0);
    return r;
  }
}

// dᵏ/dτᵏ of y(τ) for y built from taylor_variable, k ≤ depth.
template <typename T>
double taylor_derivative(const T& y, int k) {
  if constexpr (!JetInfo<T>::is_jet) {
    if (k != 0) throw std::logic_error("taylor_derivative: order above the jet depth");
    return static_cast<double>(y);
  } else {
    return k == 0 ? value_of(y) : taylor_derivative(y.v[0], k - 1);
  }
}

// σ(z) on a (nested) jet from the derivative tables σ⁽ᵐ⁾(z⁰): with δ = z − z⁰ nilpotent of
// index depth + 1, σ(z) = Σ_{m ≤ depth} σ⁽ᵐ⁾(z⁰) δᵐ / m! exactly.
template <typename T>
T apply_tables(const autodiff::ElementwiseFunction<double>& f, const T& z) {
  constexpr int depth = JetInfo<T>::depth;
  Eigen::MatrixXd z0(1, 1);
  z0(0, 0) = value_of(z);
  std::vector<Eigen::MatrixXd> tables;
  f.derivatives(z0, depth, tables);
  const T delta = z - constant<T>(z0(0, 0));
  T power = constant<T>(1.0), out = constant<T>(tables[0](0, 0));
  double factorial = 1;
  for (int m = 1; m <= depth; ++m) {
    power = power * delta;
    factorial *= m;
    out = out + constant<T>(tables[m](0, 0) / factorial) * power;
  }
  return out;
}

// tanh, the logistic sigmoid and softplus on nested jets of any depth (ceres' own tanh and
// log1p construct T(1.0) from a double, which fails for jets nested more than twice).
template <typename T>
T jet_tanh(const T& z) {
  if constexpr (!JetInfo<T>::is_jet) {
    return std::tanh(z);
  } else {
    using Inner = typename JetInfo<T>::Inner;
    const Inner t = jet_tanh(z.a);
    const Inner slope = constant<Inner>(1.0) - t * t;
    T r = constant<T>(0.0);
    r.a = t;
    for (int i = 0; i < r.v.size(); ++i) r.v[i] = slope * z.v[i];
    return r;
  }
}
template <typename T>
T jet_sigmoid(const T& z) {
  if constexpr (!JetInfo<T>::is_jet) {
    return 1.0 / (1.0 + std::exp(-z));
  } else {
    using Inner = typename JetInfo<T>::Inner;
    const Inner s = jet_sigmoid(z.a);
    const Inner slope = s * (constant<Inner>(1.0) - s);
    T r = constant<T>(0.0);
    r.a = s;
    for (int i = 0; i < r.v.size(); ++i) r.v[i] = slope * z.v[i];
    return r;
  }
}
template <typename T>
T jet_softplus(const T& z) {
  if constexpr (!JetInfo<T>::is_jet) {
    return std::log1p(std::exp(z));  // |z| stays moderate in the tests
  } else {
    using Inner = typename JetInfo<T>::Inner;
    const Inner slope = jet_sigmoid(z.a);
    T r = constant<T>(0.0);
    r.a = jet_softplus(z.a);
    for (int i = 0; i < r.v.size(); ++i) r.v[i] = slope * z.v[i];
    return r;
  }
}

// σ in closed form for the activations this header knows; `known` tells whether it did.
template <typename T>
T closed_form_activation(const std::string& name, double omega, const T& z, bool* known) {
  using std::sin;
  *known = true;
  if (name == "sine") return sin(constant<T>(omega) * z);
  if (name == "tanh") return jet_tanh(z);
  if (name == "softplus") return jet_softplus(z);
  if (name == "relu") return value_of(z) > 0 ? z : constant<T>(0.0);
  if (name == "identity") return z;
  *known = false;
  return z;
}

inline bool knows_activation(const std::string& name) {
  bool known = false;
  closed_form_activation<double>(io::to_lower(name), 1.0, 0.0, &known);
  return known;
}

class ReferenceField {
 public:
  ReferenceField(fields::FieldOptions options, Eigen::VectorXd parameters,
                 Eigen::MatrixXd encoding)
      : options_(std::move(options)),
        parameters_(std::move(parameters)),
        encoding_(std::move(encoding)) {
    siren_ = io::to_lower(options_.type) == "siren";
    bacon_ = io::to_lower(options_.type) == "bacon";
    if (bacon_) {
      check_bacon_layout();
      return;
    }
    acorn_ = io::to_lower(options_.type) == "acorn";
    cusp_ = io::to_lower(options_.encoding.type) == "cusp";
    hash_ = io::to_lower(options_.encoding.type) == "hash_grid";
    integrated_ = io::to_lower(options_.encoding.type) == "integrated_positional";
    include_input_ = hash_ || integrated_ ? keys_.include_input
                           : encoding_.rows() == 0 || cusp_ ||
                                 (io::to_lower(options_.encoding.type) == "positional" &&
                                  keys_.include_input);
    Eigen::Index width = (include_input_ ? options_.input_dim : 0) +
                         (cusp_ ? 1 : 2) * encoding_.rows();
    Eigen::Index count = 0;
    if (integrated_) {
      const Eigen::Index k = options_.input_dim / 2;
      width = (include_input_ ? k : 0) + 2 * keys_.frequencies * k;
    }
    if (hash_) {
      levels_ = fields::hash_grid_levels(options_.encoding, options_.input_dim);
      const Eigen::Index f = keys_.features_per_level;
      width = (include_input_ ? options_.input_dim : 0) + static_cast<Eigen::Index>(levels_.size()) * f;
      count = (levels_.back().first_row + levels_.back().rows) * f;
      table_count_ = count;
    }
    if (acorn_) {
      include_input_ = false;
      acorn_widths_ = acorn_encoder_widths();
      width = fields::acorn_options(options_).features;
      for (size_t l = 1; l < acorn_widths_.size(); ++l)
        count += static_cast<Eigen::Index>(acorn_widths_[l]) * (acorn_widths_[l - 1] + 1);
      table_count_ = count;
    }
    for (size_t l = 0; l < options_.hidden.size(); ++l) {
      const int h = options_.hidden[l];
      count += h * width + h;
      width = h;
      if (l == 0) {  // a latent code joins the first hidden layer's output (fields/latent_code.h)
        count += options_.latent_size;
        width += options_.latent_size;
      }
    }
    count += options_.output_dim * width + options_.output_dim;
    if (count != parameters_.size())
      throw std::logic_error("ReferenceField: layout needs " + std::to_string(count) +
                             " parameters, the field has " + std::to_string(parameters_.size()));
    for (size_t l = 0; l < options_.hidden.size(); ++l) {
      fields::ActivationSpec spec = activation(l);
      tables_.push_back(fields::make_activation<double>(spec));
    }
  }

  explicit ReferenceField(const fields::Field<double>& field)
      : ReferenceField(field.options(), field.parameters(), field.encoding_matrix()) {}

  int input_dim() const { return options_.input_dim; }
  int output_dim() const { return options_.output_dim; }
  // Inputs [variance_begin(), input_dim()) are variances (≥ 0): the integrated positional
  // encoding's; input_dim() when there are none.
  int variance_begin() const { return integrated_ ? options_.input_dim / 2 : options_.input_dim; }
  const Eigen::VectorXd& parameters() const { return parameters_; }
  ReferenceField with_parameters(Eigen::VectorXd p) const {
    return ReferenceField(options_, std::move(p), encoding_);
  }

  // The activation of hidden layer l as the field builds it.
  fields::ActivationSpec activation(size_t l) const {
    if (siren_) return {"sine", l == 0 ? options_.first_omega : options_.hidden_omega};
    return {io::to_lower(options_.activation), options_.hidden_omega};
  }

  // f(x): output_dim values.
  template <typename T>
  std::vector<T> evaluate(const std::vector<T>& x) const {
    return run<T>(x, nullptr);
  }

  // Quantities whose sign changes where the field has a kink, for keeping finite differences
  // away from kinks: pre-activations z of hidden units with a kinked activation (relu),
  // x_a − c of cusp features, sin(π p_j) of every hash-grid level and axis (zero on cell
  // faces).
  std::vector<double> preactivations(const std::vector<double>& x) const {
    std::vector<double> z;
    run<double>(x, &z);
    return z;
  }

 private:
  // The parameter count of a bacon field's layout (above), checked against the field's.
  void check_bacon_layout() {
    const auto& h = options_.hidden;
    Eigen::Index count = 0;
    for (size_t i = 0; i < h.size(); ++i) count += (i > 0 ? h[i] * h[i - 1] + h[i] : 0) + h[i];
    for (int l : fields::bacon_options(options_).head_layers(static_cast<int>(h.size())))
      count += options_.output_dim * h[static_cast<size_t>(l)] + options_.output_dim;
    if (count != parameters_.size())
      throw std::logic_error("ReferenceField: bacon layout needs " + std::to_string(count) +
                             " parameters, the field has " + std::to_string(parameters_.size()));
    omega_ = fields::bacon_filter_frequencies(options_);
  }

  template <typename T>
  std::vector<T> bacon(const std::vector<T>& x) const {
    using std::sin;
    const auto& h = options_.hidden;
    const fields::BaconOptions& b = fields::bacon_options(options_);
    const std::vector<int> heads = b.head_layers(static_cast<int>(h.size()));
    const double* p = parameters_.data();
    std::vector<std::vector<T>> z(h.size());
    for (size_t i = 0; i < h.size(); ++i) {
      std::vector<T> v;
      if (i > 0) {
        v.assign(h[i], constant<T>(0.0));
        for (int r = 0; r < h[i]; ++r) {
          T acc = constant<T>(p[h[i] * h[i - 1] + r]);
          for (int c = 0; c < h[i - 1]; ++c) acc = acc + constant<T>(p[c * h[i] + r]) * z[i - 1][c];
          v[r] = acc;
        }
        p += h[i] * h[i - 1] + h[i];
      }
      for (int r = 0; r < h[i]; ++r) {
        T u = constant<T>(p[r]);
        for (int k = 0; k < options_.input_dim; ++k) u = u + constant<T>(omega_[i](r, k)) * x[k];
        z[i].push_back(i > 0 ? sin(u) * v[r] : sin(u));
      }
      p += h[i];
    }
    const int m = options_.output_dim;
    for (size_t s = 0; s < heads.size(); ++s) {
      const auto& a = z[static_cast<size_t>(heads[s])];
      const Eigen::Index width = static_cast<Eigen::Index>(a.size());
      if (static_cast<int>(s) == b.chosen_scale()) {
        std::vector<T> y(m);
        for (int r = 0; r < m; ++r) {
          T acc = constant<T>(p[m * width + r]);
          for (Eigen::Index c = 0; c < width; ++c) acc = acc + constant<T>(p[c * m + r]) * a[c];
          y[r] = acc;
        }
        return y;
      }
      p += m * width + m;
    }
    throw std::logic_error("ReferenceField: no head for the chosen scale");
  }

  template <typename T>
  std::vector<T> run(const std::vector<T>& x, std::vector<double>* pre) const {
    using std::cos;
    using std::sin;
    const int d = options_.input_dim;
    if (static_cast<int>(x.size()) != d) throw std::logic_error("ReferenceField: wrong input size");
    if (bacon_) return bacon(x);
    std::vector<T> a;
    if (include_input_) a = x;
    if (integrated_) {
      // Written from the definition: E[sin(ω x)], E[cos(ω x)] for x ~ N(μ, σ²).
      using std::exp;
      const int k = d / 2;
      if (include_input_) a.resize(k);
      std::vector<T> sines, cosines;
      for (int l = 0; l < keys_.frequencies; ++l)
        for (int i = 0; i < k; ++i) {
          const double omega = std::ldexp(std::numbers::pi, l);
          const T damping = exp(constant<T>(-0.5 * omega * omega) * x[k + i]);
          sines.push_back(sin(constant<T>(omega) * x[i]) * damping);
          cosines.push_back(cos(constant<T>(omega) * x[i]) * damping);
        }
      a.insert(a.end(), sines.begin(), sines.end());
      a.insert(a.end(), cosines.begin(), cosines.end());
    } else if (cusp_) {
      // Written from the definition, not from encoding_matrix(): |x_a − c|.
      for (double c : keys_.at) {
        const T z = x[keys_.axis] - constant<T>(c);
        if (pre) pre->push_back(value_of(z));
        a.push_back(value_of(z) < 0 ? -z : z);
      }
    } else if (acorn_) {
      a = acorn(x, pre);
    } else if (hash_) {
      const std::vector<T> features = hash_grid(x, pre);
      a.insert(a.end(), features.begin(), features.end());
    } else if (encoding_.rows() > 0) {
      std::vector<T> z(encoding_.rows(), constant<T>(0.0));
      for (Eigen::Index r = 0; r < encoding_.rows(); ++r)
        for (int c = 0; c < d; ++c) z[r] = z[r] + constant<T>(encoding_(r, c)) * x[c];
      for (const T& zr : z) a.push_back(sin(zr));
      for (const T& zr : z) a.push_back(cos(zr));
    }
    const double* p = parameters_.data() + table_count_;
    auto dense = [&p](const std::vector<T>& in, Eigen::Index out_width) {
      const Eigen::Index in_width = static_cast<Eigen::Index>(in.size());
      std::vector<T> out(out_width);
      for (Eigen::Index r = 0; r < out_width; ++r) {
        T acc = constant<T>(p[out_width * in_width + r]);
        for (Eigen::Index c = 0; c < in_width; ++c)
          acc = acc + constant<T>(p[c * out_width + r]) * in[c];
        out[r] = acc;
      }
      p += out_width * in_width + out_width;
      return out;
    };
    for (size_t l = 0; l < options_.hidden.size(); ++l) {
      std::vector<T> z = dense(a, options_.hidden[l]);
      const fields::ActivationSpec spec = activation(l);
      for (T& zr : z) {
        if (pre && spec.name == "relu") pre->push_back(value_of(zr));
        bool known = false;
        T y = closed_form_activation<T>(spec.name, spec.frequency, zr, &known);
        zr = known ? y : apply_tables<T>(*tables_[l], zr);
      }
      a = std::move(z);
      if (l == 0) {  // the latent code: constants of the parameters
        for (int j = 0; j < options_.latent_size; ++j) a.push_back(constant<T>(p[j]));
        p += options_.latent_size;
      }
    }
    return dense(a, options_.output_dim);
  }

  // y_l(x) = Σ_corners Π_j (axis j's weight of the corner) T_l[row(corner)], level after
  // level: 2 vertices per axis weighing 1 − φ_j and φ_j, or with cubic the 4 vertices
  // c_j − 1 … c_j + 2 weighing the uniform cubic B-spline's (1 − t)³/6, (3t³ − 6t² + 4)/6,
  // (−3t³ + 3t² + 3t + 1)/6, t³/6 (vertices stored one further: they start at −1).
  template <typename T>
  std::vector<T> hash_grid(const std::vector<T>& x, std::vector<double>* pre) const {
    static constexpr std::uint32_t kPrimes[4] = {1u, 2654435761u, 805459861u, 3674653429u};
    const fields::EncodingOptions& e = options_.encoding;
    const int d = options_.input_dim, features = keys_.features_per_level;
    const std::string kind = io::to_lower(keys_.interpolation);
    const bool smooth = kind == "smoothstep", cubic = kind == "cubic";
    const int taps = cubic ? 4 : 2;
    std::vector<T> out;
    for (const fields::HashGridLevel& level : levels_) {
      const int n = level.resolution;
      std::vector<std::vector<T>> weight(d, std::vector<T>(taps));
      std::vector<std::int64_t> cell(d);
      for (int j = 0; j < d; ++j) {
        const double lo = e.lower.empty() ? 0.0 : e.lower[j];
        const double hi = e.upper.empty() ? 1.0 : e.upper[j];
        const T p = (x[j] - constant<T>(lo)) * constant<T>(n / (hi - lo)) + constant<T>(0.5);
        if (pre) pre->push_back(std::sin(std::numbers::pi * value_of(p)));
        const double c = std::clamp(std::floor(value_of(p)), 0.0, static_cast<double>(n));
        cell[j] = static_cast<std::int64_t>(c);
        const T t = p - constant<T>(c);
        if (cubic) {
          const T u = constant<T>(1.0) - t, t2 = t * t, t3 = t2 * t;
          const T sixth = constant<T>(1.0 / 6.0);
          weight[j][0] = u * u * u * sixth;
          weight[j][1] = (constant<T>(3.0) * t3 - constant<T>(6.0) * t2 + constant<T>(4.0)) * sixth;
          weight[j][2] = (constant<T>(-3.0) * t3 + constant<T>(3.0) * t2 + constant<T>(3.0) * t +
                          constant<T>(1.0)) * sixth;
          weight[j][3] = t3 * sixth;
          continue;
        }
        T phi;
        if (!smooth)
          phi = t;
        else if (value_of(t) < 0 || value_of(t) > 1)
          phi = constant<T>(value_of(t) < 0 ? 0.0 : 1.0);
        else
          phi = t * t * (constant<T>(3.0) - constant<T>(2.0) * t);
        weight[j][0] = constant<T>(1.0) - phi;
        weight[j][1] = phi;
      }
      std::vector<T> y(features, constant<T>(0.0));
      int corners = 1;
      for (int j = 0; j < d; ++j) corners *= taps;
      for (int corner = 0; corner < corners; ++corner) {
        T w = constant<T>(1.0);
        std::uint64_t dense_row = 0, stride = 1;
        std::uint32_t hash = 0;
        for (int j = 0, rest = corner; j < d; ++j, rest /= taps) {
          const int tap = rest % taps;
          w = w * weight[j][tap];
          const std::int64_t vertex = cell[j] + tap;  // stored vertex (cubic: c_j − 1 + tap, + 1)
          dense_row += static_cast<std::uint64_t>(vertex) * stride;
          stride *= static_cast<std::uint64_t>(n) + (cubic ? 4 : 2);
          hash ^= static_cast<std::uint32_t>(vertex) * kPrimes[j];
        }
        const std::uint64_t row =
            level.dense ? dense_row : hash % (std::uint64_t{1} << keys_.log2_table_size);
        for (int f = 0; f < features; ++f)
          y[f] = y[f] + w * constant<T>(parameters_[(level.first_row + row) * features + f]);
      }
      out.insert(out.end(), y.begin(), y.end());
    }
    return out;
  }

  // acorn's encoder widths: input (d + 1)(1 + 2K), hidden…, C·G^d.
  std::vector<int> acorn_encoder_widths() const {
    const fields::AcornOptions& a = fields::acorn_options(options_);
    std::vector<int> w{(options_.input_dim + 1) * (1 + 2 * a.encoder_octaves)};
    w.insert(w.end(), a.encoder_hidden.begin(), a.encoder_hidden.end());
    int grid = a.features;
    for (int j = 0; j < options_.input_dim; ++j) grid *= a.grid;
    w.push_back(grid);
    return w;
  }

  // The feature grid of block b, Φ[v·C + c] with v = Σ_j v_j G^j: q = (the block's centre
  // in [−1, 1]^d, 2·level/max_level − 1), [q, sin(2ᵏπq), cos(2ᵏπq)] octave after octave,
  // W a + b with ReLU after every layer but the last.
  // With `pre`, the encoder's hidden pre-activations (ReLU kinks in the parameters).
  std::vector<double> acorn_grid(int b, std::vector<double>* pre) const {
    const fields::AcornOptions& o = fields::acorn_options(options_);
    const fields::BlockTree& tree = *o.tree;
    const int d = options_.input_dim, n = d + 1;
    std::vector<double> q(n);
    for (int j = 0; j < d; ++j) q[j] = 2 * (tree.lower(b, j) + tree.size(b) / 2) - 1;
    q[d] = o.max_level > 0 ? 2.0 * tree.blocks()[static_cast<size_t>(b)].level / o.max_level - 1 : 0;
    std::vector<double> a = q, sines, cosines;
    for (int k = 0; k < o.encoder_octaves; ++k) {
      for (int j = 0; j < n; ++j) a.push_back(std::sin(std::ldexp(std::numbers::pi, k) * q[j]));
      for (int j = 0; j < n; ++j) a.push_back(std::cos(std::ldexp(std::numbers::pi, k) * q[j]));
    }
    const double* p = parameters_.data();
    for (size_t l = 1; l < acorn_widths_.size(); ++l) {
      const int in = acorn_widths_[l - 1], out = acorn_widths_[l];
      std::vector<double> z(out);
      for (int r = 0; r < out; ++r) {
        double acc = p[static_cast<Eigen::Index>(out) * in + r];
        for (int c = 0; c < in; ++c) acc += p[static_cast<Eigen::Index>(c) * out + r] * a[c];
        const bool hidden = l + 1 < acorn_widths_.size();
        if (pre && hidden) pre->push_back(acc);
        z[r] = hidden ? std::max(acc, 0.0) : acc;
      }
      p += static_cast<Eigen::Index>(out) * (in + 1);
      a = std::move(z);
    }
    return a;
  }

  // γ(x) = Σ_v Π_j (s_j if v_j = c_j + 1 else 1 − s_j) Φ_b[v]: p_j = (u_j − o_j)/h (G − 1)
  // with u the point in the unit cube, c_j = min(⌊p_j⌋, G − 2) (0 below the box), s = p − c.
  // Kinks: every cell face and block face is a zero of sin(π p_j).
  template <typename T>
  std::vector<T> acorn(const std::vector<T>& x, std::vector<double>* pre) const {
    const fields::AcornOptions& o = fields::acorn_options(options_);
    const fields::BlockTree& tree = *o.tree;
    const fields::EncodingOptions& e = options_.encoding;
    const int d = options_.input_dim, g = o.grid, channels = o.features;
    std::vector<T> u(d);
    double uv[3];
    for (int j = 0; j < d; ++j) {
      const double lo = e.lower.empty() ? 0.0 : e.lower[j];
      const double range = e.upper.empty() ? 1.0 : e.upper[j] - lo;
      u[j] = (x[j] - constant<T>(lo)) * constant<T>(1 / range);
      uv[j] = value_of(u[j]);
    }
    const int b = tree.locate(uv);
    const std::vector<double> grid = acorn_grid(b, pre);
    std::vector<int> cell(d);
    std::vector<T> s(d);
    for (int j = 0; j < d; ++j) {
      const T p = (u[j] - constant<T>(tree.lower(b, j))) * constant<T>((g - 1) / tree.size(b));
      if (pre) pre->push_back(std::sin(std::numbers::pi * value_of(p)));
      cell[j] = std::min(std::max(static_cast<int>(std::floor(value_of(p))), 0), g - 2);
      s[j] = p - constant<T>(cell[j]);
    }
    std::vector<T> out(channels, constant<T>(0.0));
    for (int corner = 0; corner < (1 << d); ++corner) {
      T w = constant<T>(1.0);
      int v = 0, stride = 1;
      for (int j = 0; j < d; ++j, stride *= g) {
        const bool up = (corner >> j) & 1;
        w = w * (up ? s[j] : constant<T>(1.0) - s[j]);
        v += (cell[j] + (up ? 1 : 0)) * stride;
      }
      for (int c = 0; c < channels; ++c)
        out[c] = out[c] + w * constant<T>(grid[static_cast<size_t>(v * channels + c)]);
    }
    return out;
  }

  fields::FieldOptions options_;
  AnyEncoding keys_ = any_encoding(options_.encoding);  // the encoding's own options
  Eigen::VectorXd parameters_;
  Eigen::MatrixXd encoding_;
  std::vector<Eigen::MatrixXd> omega_;  // bacon's filter frequencies
  bool bacon_ = false, acorn_ = false;
  std::vector<int> acorn_widths_;
  bool siren_ = true, cusp_ = false, hash_ = false, integrated_ = false, include_input_ = true;
  std::vector<fields::HashGridLevel> levels_;
  Eigen::Index table_count_ = 0;
  std::vector<std::shared_ptr<autodiff::ElementwiseFunction<double>>> tables_;
};

}  // namespace nfield::testutil
